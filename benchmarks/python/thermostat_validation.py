#!/usr/bin/env python3
"""The thermostats' validation alone (the suite's part `thermostats`, issue 33): rigid TIP3P
water with MRattleNoseHooverIntegrator and MRattleBussiIntegrator beside NVE and
LangevinMiddle + SETTLE (suite/thermostats.py says what is run). Writes <out>.csv and prints
the report; --splice puts the report into docs/results.md as its section.
With --study step-sizes or density it runs one of the follow-up studies instead (the potential
energy at smaller steps; the density under a barostat), writing <out>_<study>.csv; with --study
equipartition, the thermostats' rows of the equipartition table (suite/equipartition.py), merged
into <out's folder>/equipartition.csv and its report (--splice puts it into results.md).
Usage: scripts/python.sh benchmarks/python/thermostat_validation.py [--quick] [--out docs/results/thermostats]
       scripts/python.sh benchmarks/python/thermostat_validation.py --study step-sizes [--steps 1,0.5] [--ps 20] [--methods ...]
       scripts/python.sh benchmarks/python/thermostat_validation.py --study density [--ps 40]
       scripts/python.sh benchmarks/python/thermostat_validation.py --study equipartition [--splice docs/results.md]
       scripts/python.sh benchmarks/python/thermostat_validation.py --report-from docs/results/thermostats.csv ...
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import report as results_report  # noqa: E402
from suite import equipartition, thermostats  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--quick', action='store_true', help='short runs (a smoke test; no conclusions)')
    parser.add_argument('--out', default='docs/results/thermostats', help='prefix of the .csv file')
    parser.add_argument('--report-from', help='report a finished run from its CSV instead of running')
    parser.add_argument('--minutes', type=float, default=0.0, help='with --report-from: how long that run took')
    parser.add_argument('--started', help='with --report-from: when that run started (UTC, YYYY-MM-DD HH:MM)')
    parser.add_argument('--splice', help='a results.md to put the section into (replacing its own)')
    parser.add_argument('--steps', help='comma-separated step sizes in fs to run (default: all)')
    parser.add_argument('--study', choices=('step-sizes', 'density', 'equipartition'), help='run a follow-up study instead')
    parser.add_argument('--ps', type=float, help='with --study: the production length of each run (ps)')
    parser.add_argument('--threads', type=int, default=1, help='CPU platform threads')
    parser.add_argument('--methods', help='with --study step-sizes: comma-separated methods (default: the thermostats '
                        'and LangevinMiddle + SETTLE; "M-RATTLE Langevin" may be added)')
    args = parser.parse_args()
    began = time.time()
    steps = [float(x) for x in args.steps.split(',')] if args.steps else None
    extra = {'ps': args.ps} if args.ps else {}
    if args.study == 'step-sizes':
        if args.methods:
            extra['methods'] = tuple(args.methods.split(','))
        thermostats.run_step_sizes(args.quick, args.out + '_step_sizes', log, args.threads,
                                   steps or thermostats.STEP_SIZE_FS, **extra)
    elif args.study == 'density':
        thermostats.run_density(args.quick, args.out + '_density', log, args.threads, **extra)
    elif args.study == 'equipartition':
        if args.report_from:
            md = equipartition.report(equipartition.rows_from_csv(args.report_from),
                                      {'TIP3P': equipartition.MOLECULES, 'SPC/E': equipartition.MOLECULES}, False,
                                      *equipartition.LENGTHS, args.threads)
        else:
            md = equipartition.run(args.quick, os.path.join(os.path.dirname(args.out), 'equipartition'), log,
                                   args.threads, methods=equipartition.THERMOSTATS)
        finish(md, args, began, EQUIPARTITION_STAMP)
    else:
        if args.report_from:
            md = thermostats.report(thermostats.rows_from_csv(args.report_from), 895, False, 20.0, 2.0, 2.0, 1,
                                    args.minutes, *studies_beside(args.report_from))
        else:
            md = thermostats.run(args.quick, args.out, log, args.threads, steps=steps)
        finish(md, args, began, STAMP)


STAMP = ('*This section comes from `benchmarks/python/thermostat_validation.py` (the suite\'s `thermostats` part '
         'alone), run on %s UTC; the other sections come from the runs they name.*\n')
EQUIPARTITION_STAMP = ('*The rows of the two thermostats come from `benchmarks/python/thermostat_validation.py '
                       '--study equipartition`, run on %s UTC; the other rows from the run of the suite\'s '
                       '`equipartition` part that docs/results/equipartition.csv last recorded; the other sections '
                       'come from the runs they name.*\n')


def log(text):
    print(text, flush=True)


def studies_beside(path):
    """The follow-up studies' rows (step sizes, density) from the CSVs beside a main run's, if there."""
    stem = path[:-len('.csv')]
    return [thermostats.rows_from_csv(stem + suffix) if os.path.exists(stem + suffix) else None
            for suffix in ('_step_sizes.csv', '_density.csv')]


def finish(md, args, began, stamp):
    """Print the report; with --splice, put it into that results.md as its section."""
    print('\n'.join(md))
    if args.splice:
        when = args.started or time.strftime('%Y-%m-%d %H:%M', time.gmtime(began))
        with open(args.splice) as stream:
            text = results_report.splice_sections(stream.read(), '\n'.join(md), stamp % when)
        with open(args.splice, 'w') as stream:
            stream.write(text)


if __name__ == '__main__':
    main()
