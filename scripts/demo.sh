#!/usr/bin/env bash
# The demo: install what is missing and build (scripts/build.sh), then run the 27-benzene
# NVE example with the build tree's Python module (scripts/python.sh). Extra arguments go to
# the example, e.g. scripts/demo.sh --steps 2000 --platform Reference. Output lands in ./output.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh"
exec "$root/scripts/python.sh" "$root/examples/benzene_cluster.py" "$@"
