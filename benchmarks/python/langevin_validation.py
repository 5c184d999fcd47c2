#!/usr/bin/env python3
"""Validation of MRattleLangevinIntegrator on OpenMM's own inputs (issue 10), against
OpenMM's LangevinMiddleIntegrator with SETTLE on the same System:

1. rigid TIP3P water (openmm/app/data/tip3p.pdb, amber14/tip3p.xml, PME) at 300 K: kinetic,
   translational and rotational temperatures, potential energy per molecule, the O-O radial
   distribution's first peak;
2. the same at 1 bar with a MonteCarloBarostat: the density;
3. rigid liquid benzene (mrattle.models.benzeneLiquid) at 298 K at 2, 4 and 8 fs:
   translational and rotational temperatures; the largest step that stays stable.

Means carry standard errors from block averages (10 blocks, each much longer than the
correlation times). Writes a markdown report and a CSV. CPU platform.
Usage: PYTHONPATH=build/python python3 benchmarks/python/langevin_validation.py [--quick] [--out docs/results/langevin]
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite import langevin  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--quick', action='store_true', help='short runs (a smoke test; no conclusions)')
    parser.add_argument('--out', default='docs/results/langevin', help='prefix of the .md and .csv files')
    args = parser.parse_args()
    report = langevin.run(args.quick, args.out, lambda text: print(text, flush=True))
    with open(args.out + '.md', 'w') as stream:
        stream.write('\n'.join(report) + '\n')
    print('\n'.join(report))


if __name__ == '__main__':
    main()
