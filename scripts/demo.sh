#!/usr/bin/env bash
# The main job on the built-in default: builds everything (the native hawor CLI and default hands,
# the WebAssembly core, the synthetic sample clip: scripts/build_web.sh), runs the whole pipeline
# headless on the sample (node web/cli.mjs run --sample -> hawor-demo/: world.npz, camera.tum,
# hands_cam.npz, result.json), then serves the browser app on http://127.0.0.1:${PORT:-8080}/
# (Ctrl-C stops it). HAWOR_NO_SERVE=1 stops after the headless run.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
source scripts/native_compiler.sh
# cmake's own progress lines show while it builds (a few minutes on a fresh machine, seconds after).
if [[ ! -f build/native/CMakeCache.txt ]]; then
  echo "[demo] configuring build/native (cmake)" >&2
  env $(native_compiler_env) cmake -S . -B build/native -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
echo "[demo] building the native hawor tool (build/native)" >&2
cmake --build build/native --target hawor_cli default_hands -j"$(nproc)"
bash scripts/build_web.sh
# --sample: the built-in synthetic clip with its true focal (sample.json); `npx hawor run --sample`
# in an installed package.
echo "[demo] node web/cli.mjs run --sample --out hawor-demo" >&2
node web/cli.mjs run --sample --out hawor-demo
if [[ "${HAWOR_NO_SERVE:-0}" != 1 ]]; then
  exec node web/server.mjs --port "${PORT:-8080}" --host "${HOST:-127.0.0.1}"
fi
