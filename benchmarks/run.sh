#!/usr/bin/env bash
# Build what is missing, then run the benchmark suite: ./benchmarks/run.sh [--quick] [--only parts]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh" > /dev/null
exec /usr/bin/python3 "$root/benchmarks/run_suite.py" --build "${MRATTLE_BUILD_DIR:-$root/build}" "$@"
