#!/usr/bin/env python3
"""The thermostats' validation alone (the suite's part `thermostats`, issue 33): rigid TIP3P
water with MRattleNoseHooverIntegrator and MRattleBussiIntegrator beside NVE and
LangevinMiddle + SETTLE (suite/thermostats.py says what is run). Writes <out>.csv and prints
the report; --splice puts the report into docs/results.md as its section.
Usage: scripts/python.sh benchmarks/python/thermostat_validation.py [--quick] [--out docs/results/thermostats]
       scripts/python.sh benchmarks/python/thermostat_validation.py --report-from docs/results/thermostats.csv ...
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import report as results_report  # noqa: E402
from suite import thermostats  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--quick', action='store_true', help='short runs (a smoke test; no conclusions)')
    parser.add_argument('--out', default='docs/results/thermostats', help='prefix of the .csv file')
    parser.add_argument('--report-from', help='report a finished run from its CSV instead of running')
    parser.add_argument('--minutes', type=float, default=0.0, help='with --report-from: how long that run took')
    parser.add_argument('--started', help='with --report-from: when that run started (UTC, YYYY-MM-DD HH:MM)')
    parser.add_argument('--splice', help='a results.md to put the section into (replacing its own)')
    parser.add_argument('--steps', help='comma-separated step sizes in fs to run (default: all)')
    args = parser.parse_args()
    began = time.time()
    if args.report_from:
        md = thermostats.report(thermostats.rows_from_csv(args.report_from), 895, False, 20.0, 2.0, 2.0, 1,
                                args.minutes)
    else:
        steps = [float(x) for x in args.steps.split(',')] if args.steps else None
        md = thermostats.run(args.quick, args.out, lambda text: print(text, flush=True), steps=steps)
    print('\n'.join(md))
    if args.splice:
        stamp = ('*This section comes from `benchmarks/python/thermostat_validation.py` (the suite\'s `thermostats` '
                 'part alone), run on %s UTC; the other sections come from the runs they name.*\n'
                 % (args.started or time.strftime('%Y-%m-%d %H:%M', time.gmtime(began))))
        with open(args.splice) as stream:
            text = results_report.splice_sections(stream.read(), '\n'.join(md), stamp)
        with open(args.splice, 'w') as stream:
            stream.write(text)


if __name__ == '__main__':
    main()
