#!/usr/bin/env bash
# Configure and build into ./build (or $MRATTLE_BUILD_DIR). Installs missing packages first.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/install-deps.sh"
build="${MRATTLE_BUILD_DIR:-$root/build}"
mkdir -p "$build"
log="$build/configure.log"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release > "$log" 2>&1 || {
    cat "$log"; exit 1; }
cmake --build "$build" -j"$(nproc)"
