#!/usr/bin/env bash
# The main job on the built-in default: builds the native hawor tool and runs its example.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
source scripts/native_compiler.sh
env $(native_compiler_env) cmake -S . -B build/native -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build/native --target hawor_cli -j"$(nproc)" >/dev/null
build/native/examples/hawor demo --out hawor-demo
