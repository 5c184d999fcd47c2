#!/usr/bin/env bash
# The one door to the benchmarks (docs/benchmarks.md). Builds what is missing, then:
#     ./benchmarks/run.sh speed [--platform NAME] [--precision P] [--out DIR] [--quick]
#         this plugin against OpenMM's own integrators on this machine: rigid TIP3P water, M-RATTLE
#         against Verlet + SETTLE and LangevinMiddle + SETTLE (device platforms: benchmarks/cpp/device_speed,
#         the integration's own cost and ns/day with PME; CPU and Reference: benchmarks/python/suite/cost.py)
#     ./benchmarks/run.sh paper|validate-<study> [options]          the suite (benchmarks/python/run_suite.py)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${MRATTLE_BUILD_DIR:-$root/build}"
"$root/scripts/build.sh" > /dev/null
target="${1:-}"
[ $# -gt 0 ] && shift
if [ "$target" != speed ]; then
    exec "$root/scripts/python.sh" "$root/benchmarks/python/run_suite.py" "$target" --build "$build" "$@"
fi

# speed: the platform (default the last device platform the plugin runs on here, else CPU) and precision.
platform="" precisions="single double" out="$build/speed" quick=""
while [ $# -gt 0 ]; do
    case "$1" in
        --platform) platform="$2"; shift 2 ;;
        --precision) precisions="$2"; shift 2 ;;
        --out) out="$2"; shift 2 ;;
        --quick) quick=1; shift ;;
        *) sed -n '2,8p' "$0"; exit 1 ;;
    esac
done
[ -n "$platform" ] || platform="$("$root/scripts/python.sh" -c \
    "import mrattle; print((mrattle.DEVICE_PLATFORMS or ['CPU'])[-1])")"
mkdir -p "$out"
echo "speed: M-RATTLE plugin $("$root/scripts/python.sh" -c 'import mrattle; print(mrattle.__version__)'), $platform; CSVs in $out" >&2
if [ "$platform" = CPU ] || [ "$platform" = Reference ]; then
    # Forces excluded: 1000 and 3000 rigid waters (k = 3) and 5-atom bodies, 1 and 2 threads.
    PYTHONPATH="$root/benchmarks/python" exec "$root/scripts/python.sh" -m suite.cost --platforms "$platform" \
        --integrators verlet,mrattle,verlet_settle,verlet_ccma --out "$out" \
        $([ -n "$quick" ] && echo --bodies 50 --repeats 2 --batch-seconds 0.01)
fi
speed=("$build/benchmarks/cpp/device_speed" --platform "$platform" --batch-seconds 0.5)
[ -n "$quick" ] && speed=("$build/benchmarks/cpp/device_speed" --platform "$platform" --batch-seconds 0.2 --repeats 2)
for precision in $precisions; do
    # Bare (the integration's own cost): 512 and 4,096 waters, 9 interleaved batches.
    "${speed[@]}" --precision "$precision" --systems bare --waters-per-side $([ -n "$quick" ] && echo 6 || echo 8,16 --repeats 9) \
        --out "$out/$precision.csv" --ratios "$out/$precision-ratios.csv"
    # PME: the integration is a small part of a step, and one Context differs from another of the same
    # integrator by up to 2%: three processes (fresh Contexts) of 7 batches, their ratios pooled.
    for process in 1 2 3; do
        "${speed[@]}" --precision "$precision" --systems pme --waters-per-side $([ -n "$quick" ] && echo 6 || echo 8 --repeats 7) \
            --out "$out/$precision-pme-$process.csv" --ratios "$out/$precision-pme-$process-ratios.csv"
    done
    awk -F, 'FNR > 1 { n[$3]++; sum[$3] += log($4); if (!($3 in low) || $4 < low[$3]) low[$3] = $4;
                       if ($4 > high[$3]) high[$3] = $4; key[$3] = $1 "," $2 }
             END { print "system,atoms,measure,value,target,processes,lowest,highest";
                   for (m in n) printf "%s,%s,%.3f,>= 0.97,%d,%s,%s\n", key[m], m, exp(sum[m] / n[m]), n[m], low[m], high[m] }' \
        "$out/$precision"-pme-[123]-ratios.csv > "$out/$precision-pme-ratios.csv"
    cat "$out/$precision-ratios.csv" "$out/$precision-pme-ratios.csv"
done
