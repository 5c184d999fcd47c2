#!/usr/bin/env bash
# Run Python with a build's module: the interpreter CMake chose (the one that has openmm, from
# the build's CMakeCache.txt) with <build>/python first on PYTHONPATH. The build is ./build or
# $MRATTLE_BUILD_DIR; it must exist (scripts/build.sh). E.g. scripts/python.sh -m mrattle.testInstallation
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${MRATTLE_BUILD_DIR:-$root/build}"
[ -f "$build/CMakeCache.txt" ] || { echo "scripts/python.sh: no build in $build (run scripts/build.sh)" >&2; exit 1; }
python="$(sed -n 's/^Python3_EXECUTABLE:[A-Z]*=//p' "$build/CMakeCache.txt")"
PYTHONPATH="$build/python${PYTHONPATH:+:$PYTHONPATH}" exec "${python:-/usr/bin/python3}" "$@"
