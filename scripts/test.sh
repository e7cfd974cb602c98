#!/usr/bin/env bash
# Runs every test: native (Release), the JavaScript tests under node (tests/web), parsers under
# ASan+UBSan (+ libFuzzer briefly, clang), the same unit tests compiled to WebAssembly under
# node, the browser app in headless Chromium (tests/browser), the npm package packed, installed
# and run (tests/package), the README's commands (tests/docs), and `hawor batch` as a job array
# on a single-node Slurm started on localhost (tests/cluster). Ends with "N passed, N failed".
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
jobs=${HAWOR_JOBS:-$(nproc)}
total_pass=0
total_fail=0
status=0
log_dir=build/test-logs
mkdir -p "$log_dir"

# native_compiler_env: CC=... CXX=... for the native build (scripts/native_compiler.sh).
source "$root/scripts/native_compiler.sh"

# run_suite NAME CONFIGURE-COMMAND...: configure, build, ctest; tallies ctest's summary.
run_suite() {
  local name=$1; shift
  local dir=build/$name t0=$SECONDS
  echo "=== [$name] configure + build" >&2
  if ! "$@" -S . -B "$dir" >"$log_dir/$name-configure.log" 2>&1; then
    tail -30 "$log_dir/$name-configure.log" >&2; echo "[$name] configure FAILED" >&2
    total_fail=$((total_fail + 1)); status=1; return
  fi
  if ! cmake --build "$dir" -j"$jobs" >"$log_dir/$name-build.log" 2>&1; then
    grep -E "error|Error" "$log_dir/$name-build.log" | head -30 >&2; echo "[$name] build FAILED" >&2
    total_fail=$((total_fail + 1)); status=1; return
  fi
  echo "=== [$name] built in $((SECONDS - t0)) s; ctest" >&2
  ctest --test-dir "$dir" --output-on-failure -j"$jobs" 2>&1 | tee "$log_dir/$name-ctest.log"
  local line pass fail of
  line=$(grep -E "tests passed, [0-9]+ tests failed out of [0-9]+" "$log_dir/$name-ctest.log" | tail -1)
  if [[ -z "$line" ]]; then
    echo "[$name] no ctest summary" >&2; total_fail=$((total_fail + 1)); status=1; return
  fi
  fail=$(sed -E 's/.* ([0-9]+) tests failed out of ([0-9]+).*/\1/' <<<"$line")
  of=$(sed -E 's/.* ([0-9]+) tests failed out of ([0-9]+).*/\2/' <<<"$line")
  pass=$((of - fail))
  total_pass=$((total_pass + pass)); total_fail=$((total_fail + fail))
  ((fail == 0)) || status=1
  echo "=== [$name] done in $((SECONDS - t0)) s" >&2
}

# tally_node NAME LOG RC: adds node's TAP summary ("# pass N" / "# fail N") in LOG to the totals;
# a missing summary, or a non-zero exit without failures (a crash after the tests), is a failure.
tally_node() {
  local name=$1 log=$2 rc=$3 pass fail
  pass=$(grep -E '^# pass [0-9]+$' "$log" | tail -1 | awk '{print $3}')
  fail=$(grep -E '^# fail [0-9]+$' "$log" | tail -1 | awk '{print $3}')
  if [[ -z "$pass" || -z "$fail" ]]; then
    echo "[$name] no test summary" >&2; total_fail=$((total_fail + 1)); status=1; return
  fi
  total_pass=$((total_pass + pass)); total_fail=$((total_fail + fail))
  if ((fail == 0 && rc != 0)); then
    echo "[$name] node --test exited $rc" >&2; total_fail=$((total_fail + 1))
  fi
  ((fail == 0 && rc == 0)) || status=1
}

# run_node_suite: the JavaScript tests (tests/web, node's own runner, onnxruntime-web's wasm
# build) against the native binary and the WebAssembly core (hawor_core.mjs) just built. The
# files are listed by the shell (node 18 and 20 also take the folder, node 22 only patterns);
# no flag is needed on node 18 or 20 (onnxruntime-web reads its .wasm from disk in node).
run_node_suite() {
  echo "=== [node] node --test tests/web" >&2
  local t0=$SECONDS
  if [[ ! -f node_modules/onnxruntime-web/package.json ]]; then
    echo "[node] node_modules/onnxruntime-web missing: run scripts/install.sh" >&2
    total_fail=$((total_fail + 1)); status=1; return
  fi
  # Test files at once, one per core (node >= 20.10; its default is one fewer than the cores:
  # one file at a time on two); each file has its own temporary folders.
  local conc=()
  if node --help 2>/dev/null | grep -q -- '--test-concurrency'; then conc=(--test-concurrency="$jobs"); fi
  HAWOR_BIN="$root/build/native/examples/hawor" HAWOR_CORE="$root/build/wasm/wasm/hawor_core.mjs" \
    node --test "${conc[@]}" --test-reporter=tap tests/web/*.test.mjs 2>&1 | tee "$log_dir/node-test.log"
  tally_node node "$log_dir/node-test.log" "${PIPESTATUS[0]}"
  echo "=== [node] done in $((SECONDS - t0)) s" >&2
}

# run_node_stage NAME FILES...: node's test runner over FILES, its TAP summary tallied as NAME.
run_node_stage() {
  local name=$1 t0=$SECONDS; shift
  node --test --test-reporter=tap "$@" 2>&1 | tee "$log_dir/$name-test.log"
  tally_node "$name" "$log_dir/$name-test.log" "${PIPESTATUS[0]}"
  echo "=== [$name] done in $((SECONDS - t0)) s" >&2
}

# The stages after the builds, in this order (each uses what the one before built):
#   browser  the app end to end in headless Chromium (tests/browser; its WebGPU test beside
#            package and readme): scripts/build_web.sh adds
#            the synthetic sample (build/web), then node's runner drives Debian's chromium
#            through playwright-core;
#   package  the npm package (tests/package): npm pack (its prepack stages the WebAssembly core
#            and the sample into dist/), an install of the tarball into an empty folder (npm's
#            registry or its cache, warm after scripts/install.sh), the installed `hawor` CLI on
#            the sample and imports of its modules;
#   readme   the README's commands as written (tests/docs: every sh block but the suite itself
#            and the one that needs the user's MANO files). It packs too, so it runs after
#            package, not beside it (npm pack rewrites dist/).
run_late_stages() {
  echo "=== [browser] scripts/build_web.sh + node --test tests/browser" >&2
  if ! HAWOR_JOBS="$jobs" bash scripts/build_web.sh >"$log_dir/browser-build.log" 2>&1; then
    tail -20 "$log_dir/browser-build.log" >&2; echo "[browser] build_web.sh FAILED" >&2
    total_fail=$((total_fail + 1)); status=1; return
  fi
  local browser_tests=() f
  for f in tests/browser/*.test.mjs; do [[ $f == */webgpu.test.mjs ]] || browser_tests+=("$f"); done
  run_node_stage browser "${browser_tests[@]}"
  # The WebGPU test (SwiftShader: seconds per inference, no timing asserted) runs beside package
  # and readme, which mostly wait on npm and child processes; the app's tests above time the page.
  background webgpu run_webgpu_stage
  echo "=== [package] node --test tests/package" >&2
  run_node_stage package tests/package/*.test.mjs
  echo "=== [readme] node --test tests/docs" >&2
  run_node_stage readme tests/docs/*.test.mjs
  collect webgpu
}

run_webgpu_stage() {
  echo "=== [webgpu] node --test tests/browser/webgpu.test.mjs" >&2
  run_node_stage webgpu tests/browser/webgpu.test.mjs
}

# run_sanitize_suite: the parsers under ASan + UBSan (its own build folder, nothing shared).
run_sanitize_suite() {
  if command -v clang++ >/dev/null; then
    run_suite sanitize env CC=clang CXX=clang++ cmake -DCMAKE_BUILD_TYPE=Debug -DHAWOR_SANITIZE=ON -DHAWOR_FUZZ=ON -DHAWOR_BUILD_EXAMPLES=OFF
  else
    run_suite sanitize cmake -DCMAKE_BUILD_TYPE=Debug -DHAWOR_SANITIZE=ON -DHAWOR_BUILD_EXAMPLES=OFF
  fi
}

# The native suite builds with clang when installed (the sanitizer and WebAssembly builds use it
# too): clang 14 compiles this Eigen-heavy template code at -O1 in ~0.55x g++ 12's CPU time
# (test_motion's unity file: 71 s vs 127 s). scripts/demo.sh makes the same choice, so the two
# share build/native. HAWOR_NATIVE_CXX=g++ (or any compiler) overrides it.
run_suite native env $(native_compiler_env) cmake -DCMAKE_BUILD_TYPE=Release
run_suite wasm emcmake cmake -DCMAKE_BUILD_TYPE=Release
# background NAME FUNCTION: runs FUNCTION in a background subshell, its output into a log that
# collect NAME prints when it is done; the tallies come back through a file (a background
# subshell has its own counters).
background() {
  local name=$1 fn=$2
  rm -f "$log_dir/$name.tally"
  (
    total_pass=0 total_fail=0 status=0
    "$fn"
    echo "$total_pass $total_fail $status" >"$log_dir/$name.tally"
  ) >"$log_dir/$name-stage.log" 2>&1 &
  eval "${name}_pid=$!"
}
collect() {
  local name=$1 pid_var="${1}_pid" sp sf ss
  wait "${!pid_var}"
  cat "$log_dir/$name-stage.log"
  if [[ -f "$log_dir/$name.tally" ]] && read -r sp sf ss <"$log_dir/$name.tally"; then
    total_pass=$((total_pass + sp)); total_fail=$((total_fail + sf))
    ((ss == 0)) || status=1
  else
    echo "[$name] no tally" >&2; total_fail=$((total_fail + 1)); status=1
  fi
}

# run_cluster_stage: hawor batch as a Slurm job array on a single-node cluster on localhost
# (tests/cluster). Debian's slurmctld, slurmd, slurm-client and munge are installed here rather
# than by scripts/install.sh (their packages would start services on a user's machine); without
# them, or where the daemons cannot start, the test skips with the reason.
run_cluster_stage() {
  echo "=== [cluster] tests/cluster/slurm_local.sh install + node --test tests/cluster" >&2
  bash tests/cluster/slurm_local.sh install 2>&1 || echo "[cluster] Slurm could not be installed: its test skips" >&2
  run_node_stage cluster tests/cluster/*.test.mjs
}

# The sanitizer stage runs beside the node suite (after the WebAssembly build: the pipeline tests,
# tests/web/pipeline.test.mjs, run its hawor_core.mjs), which leaves about a fifth of two cores
# idle while its files wait on their child processes. The cluster stage runs beside the late
# stages: it mostly waits on Slurm, and none of them measures time.
background sanitize run_sanitize_suite
run_node_suite
collect sanitize
background cluster run_cluster_stage
run_late_stages
collect cluster

echo "$total_pass passed, $total_fail failed"
exit $status
