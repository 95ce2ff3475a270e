#!/usr/bin/env bash
# Configures and builds OpenPhaco (Release, portable flags) into build/release.
# Usage: scripts/build.sh [extra cmake -D options...]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${PHACO_BUILD_DIR:-$root/build/release}"
jobs="${PHACO_JOBS:-$(nproc)}"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build" -j "$jobs"
