#!/usr/bin/env bash
# Builds the browser app (scripts/build_web.sh) and serves it on http://127.0.0.1:${PORT:-8080}/
# (HOST overrides 127.0.0.1). Stops with Ctrl-C. Everything runs in the browser; the server only
# hands out the page, the WebAssembly core, the ONNX networks and the sample.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
bash scripts/build_web.sh
exec node web/server.mjs --port "${PORT:-8080}" --host "${HOST:-127.0.0.1}"
