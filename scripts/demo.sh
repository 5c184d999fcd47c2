#!/usr/bin/env bash
# The demo: install what is missing and build (scripts/build.sh), then run the 27-benzene
# NVE example with the build tree's Python module. Extra arguments go to the example,
# e.g. scripts/demo.sh --steps 2000 --platform Reference. Output lands in ./output.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh"
build="${MRATTLE_BUILD_DIR:-$root/build}"
# The interpreter CMake chose: the one that has openmm.
python="$(sed -n 's/^Python3_EXECUTABLE:[A-Z]*=//p' "$build/CMakeCache.txt")"
PYTHONPATH="$build/python${PYTHONPATH:+:$PYTHONPATH}" "${python:-/usr/bin/python3}" "$root/examples/benzene_cluster.py" "$@"
