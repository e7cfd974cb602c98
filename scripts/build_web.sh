#!/usr/bin/env bash
# Builds what the browser app serves (nothing of it is committed):
#   build/wasm/wasm/hawor_core.{mjs,wasm}   the C++ core (emscripten)
#   build/web/sample.webm + sample.json     the built-in synthetic sample (hawor synth, VP9)
# and converts the hand networks into web/models/ when missing (as scripts/install.sh does). The app's
# default hand is the WebXR glTF hand of node_modules (@webxr-input-profiles/assets), read as is;
# web/server.mjs serves these at /dist/ and /node_modules/, as an installed npm package lays them out.
# Environment: HAWOR_NATIVE_BUILD (default build/native: the hawor CLI and its models/),
# HAWOR_JOBS (default: the number of CPUs).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
jobs=${HAWOR_JOBS:-$(nproc)}
native=${HAWOR_NATIVE_BUILD:-$root/build/native}
hawor="$native/examples/hawor"
out=build/web

if [[ ! -x "$hawor" ]]; then
  echo "[build_web] native hawor CLI ($native)" >&2
  source scripts/native_compiler.sh
  [[ -f "$native/CMakeCache.txt" ]] || env $(native_compiler_env) cmake -S . -B "$native" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$native" --target hawor_cli default_hands -j"$jobs"
fi

if [[ ! -f build/wasm/CMakeCache.txt ]]; then
  echo "[build_web] configuring build/wasm (emscripten)" >&2
  emcmake cmake -S . -B build/wasm -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
echo "[build_web] hawor_core (WebAssembly; about 2 minutes on two cores when it is not built yet)" >&2
cmake --build build/wasm --target hawor_core -j"$jobs"

for m in palm_detection_lite palm_detection_full hand_landmark_lite hand_landmark_full; do
  if [[ ! -f "web/models/$m.onnx" ]]; then
    # The same conversion scripts/install.sh runs (< 1 s; fails with a message naming what is missing).
    node web/tools/convert_mediapipe.mjs --out web/models
    break
  fi
done

mkdir -p "$out"

# The synthetic sample: 60 frames of the table_work preset (seed 1), 640x480 at 30 fps, VP9.
if [[ ! -f "$out/sample.webm" || ! -f "$out/sample.json" ]]; then
  echo "[build_web] synthetic sample (hawor synth --preset table_work --seed 1 --frames 60)" >&2
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  "$hawor" synth --preset table_work --seed 1 --frames 60 --out "$tmp/seq" >/dev/null
  read -r fx fy cx cy w h fps < "$tmp/seq/intrinsics.txt"
  ffmpeg -v error -y -framerate "$fps" -i "$tmp/seq/rgb/%06d.png" -c:v libvpx-vp9 -b:v 0 -crf 24 \
         -deadline good -cpu-used 4 -row-mt 1 -pix_fmt yuv420p "$tmp/sample.webm"
  mv "$tmp/sample.webm" "$out/sample.webm"
  printf '{"video": "sample.webm", "preset": "table_work", "seed": 1, "frames": 60, "fps": %s, "width": %s, "height": %s, "fx": %s, "fy": %s, "cx": %s, "cy": %s}\n' \
    "$fps" "$w" "$h" "$fx" "$fy" "$cx" "$cy" > "$out/sample.json"
fi
echo "[build_web] ready: build/web ($(ls "$out" | tr '\n' ' '))" >&2
