#!/usr/bin/env bash
# Build what is missing, then run the benchmark suite (benchmarks/python/run_suite.py) with the
# interpreter the build chose, as the demo does (scripts/python.sh):
#     ./benchmarks/run.sh [--quick] [--only parts]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh" > /dev/null
exec "$root/scripts/python.sh" "$root/benchmarks/python/run_suite.py" --build "${MRATTLE_BUILD_DIR:-$root/build}" "$@"
