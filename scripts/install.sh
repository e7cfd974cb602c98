#!/usr/bin/env bash
# Installs everything hawor needs on a fresh Debian 12 machine (run as root; apt + npm only).
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
pkgs=(build-essential cmake git pkg-config
      libeigen3-dev catch2 libstb-dev          # the library's headers and tests
      emscripten nodejs                        # the WebAssembly build and its runtime
      clang libclang-rt-14-dev                 # libFuzzer targets and sanitizers
      python3 python3-numpy python3-scipy)     # independent references run by the tests
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "[install] apt-get install ${missing[*]}" >&2
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
# npm (Debian's nodejs package has none; nodesource's nodejs ships its own).
if ! command -v npm >/dev/null; then
  apt-get install -y -qq --no-install-recommends npm >/dev/null
fi
# npm packages of package.json (exact versions): the licence-free default hand (MIT) ...
root=$(cd "$(dirname "$0")/.." && pwd)
if [[ ! -f "$root/node_modules/@webxr-input-profiles/assets/package.json" ]]; then
  echo "[install] npm install" >&2
  (cd "$root" && npm install --no-audit --no-fund --loglevel=error >/dev/null)
fi
echo "[install] toolchain ready: $(cmake --version | head -1); $(em++ --version 2>/dev/null | head -1 | cut -c1-60); node $(node --version)" >&2
