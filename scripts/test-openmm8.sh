#!/usr/bin/env bash
# The C++ suite against another OpenMM install (default: ../shared/openmm-8.5.2, a C++-only
# OpenMM 8.5.2 build with the Reference and CPU platforms): configure a second build in
# ./build-openmm8 (or $MRATTLE_OPENMM8_BUILD_DIR) with Python off, build, run CTest.
# Usage: scripts/test-openmm8.sh [OPENMM_DIR]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
openmm="${1:-$root/../shared/openmm-8.5.2}"
if [ ! -d "$openmm" ]; then
    echo "No OpenMM install at $openmm: nothing to test against"; exit 1
fi
openmm="$(cd "$openmm" && pwd)"
"$root/scripts/install-deps.sh"
build="${MRATTLE_OPENMM8_BUILD_DIR:-$root/build-openmm8}"
mkdir -p "$build"
log="$build/configure.log"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DOPENMM_DIR="$openmm" -DMRATTLE_BUILD_PYTHON=OFF > "$log" 2>&1 || {
    cat "$log"; exit 1; }
grep -- "-- OpenMM " "$log"
cmake --build "$build" -j"$(nproc)"
cd "$build"
ctest --output-on-failure -j"$(nproc)"
