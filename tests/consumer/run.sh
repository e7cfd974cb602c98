#!/usr/bin/env bash
# Builds tests/consumer outside hawor's build and runs it, one way per call (ctest runs each as a
# test, see tests/CMakeLists.txt):
#   run.sh install      WORK   cmake --install of a headers-only configure into WORK/prefix
#   run.sh subdirectory WORK   add_subdirectory(hawor checkout); stb on
#   run.sh package      WORK   find_package(hawor) from WORK/prefix with HAWOR_WITH_STB=OFF
#   run.sh wasm         WORK   the same package under emcmake, run under node; stb on
# HAWOR_HAND_MODEL names the hand model the program loads (default: the npm default right hand).
set -euo pipefail
mode=${1:?mode}
work=${2:?work folder}
root=$(cd "$(dirname "$0")/../.." && pwd)
src="$root/tests/consumer"
prefix="$work/prefix"
hand=${HAWOR_HAND_MODEL:-$root/node_modules/@webxr-input-profiles/assets/dist/profiles/generic-hand/right.glb}
mkdir -p "$work"
# No build type (no optimisation): the program checks results, not speed, and compiles in about
# half the time. CXX (ctest passes the compiler of hawor's own build) picks the compiler.
cfg=(-DCMAKE_BUILD_TYPE=)

need_hand() {
  [[ -f "$hand" ]] || { echo "run.sh: $hand missing (scripts/install.sh installs the default hand)" >&2; exit 1; }
}

case "$mode" in
  install)
    rm -rf "$work/hawor-build" "$prefix"
    cmake -S "$root" -B "$work/hawor-build" "${cfg[@]}" -DHAWOR_BUILD_TESTS=OFF -DHAWOR_BUILD_EXAMPLES=OFF
    cmake --install "$work/hawor-build" --prefix "$prefix"
    # Header-only: headers and the CMake package, nothing compiled.
    test -f "$prefix/share/cmake/hawor/haworConfig.cmake"
    test -f "$prefix/share/cmake/hawor/haworConfigVersion.cmake"
    test -f "$prefix/include/hawor/hawor.hpp"
    if compiled=$(find "$prefix" -type f \( -name '*.a' -o -name '*.so*' -o -name '*.o' \) | head -1) && [[ -n "$compiled" ]]; then
      echo "run.sh: the install holds a compiled file: $compiled" >&2; exit 1
    fi
    ;;
  subdirectory)
    need_hand
    rm -rf "$work/sub"
    cmake -S "$src" -B "$work/sub" "${cfg[@]}" -DHAWOR_CONSUME=subdirectory -DHAWOR_SOURCE_DIR="$root"
    # hawor as a subproject builds none of its tests, tools or WebAssembly core.
    if [[ -d "$work/sub/hawor/tests" || -d "$work/sub/hawor/examples" ]]; then
      echo "run.sh: add_subdirectory(hawor) configured its tests or tools" >&2; exit 1
    fi
    cmake --build "$work/sub"
    "$work/sub/consumer" "$hand" stb=on
    ;;
  package)
    need_hand
    rm -rf "$work/pkg"
    cmake -S "$src" -B "$work/pkg" "${cfg[@]}" -DCMAKE_PREFIX_PATH="$prefix" -DHAWOR_WITH_STB=OFF
    cmake --build "$work/pkg"
    "$work/pkg/consumer" "$hand" stb=off
    ;;
  wasm)
    need_hand
    rm -rf "$work/wasm"
    # Under Emscripten's toolchain every package search is re-rooted: the prefix is a root.
    emcmake cmake -S "$src" -B "$work/wasm" "${cfg[@]}" -DCMAKE_FIND_ROOT_PATH="$prefix"
    cmake --build "$work/wasm"
    # consumer.js is CommonJS; when WORK lies inside this checkout, node would take the
    # repository's package.json ("type": "module") for it: a package.json beside it says otherwise.
    echo '{"type": "commonjs"}' >"$work/wasm/package.json"
    # Node 20 needs --no-experimental-fetch to load Emscripten 3.1.6 modules.
    node --no-experimental-fetch "$work/wasm/consumer.js" "$hand" stb=on
    ;;
  *)
    echo "run.sh: unknown mode '$mode' (install, subdirectory, package, wasm)" >&2; exit 2 ;;
esac
