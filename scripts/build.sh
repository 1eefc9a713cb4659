#!/usr/bin/env bash
# Configures and builds clutterscope into build/ (Release). Extra arguments go to cmake.
# Uses ccache when it is installed.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="${CLUTTERSCOPE_BUILD_JOBS:-$(nproc)}"
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@" >/dev/null
cmake --build build --parallel "$jobs"
