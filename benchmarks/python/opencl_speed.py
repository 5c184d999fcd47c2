#!/usr/bin/env python3
"""Speed on OpenMM's OpenCL platform: M-RATTLE against OpenMM's VerletIntegrator with SETTLE
on the same platform, in the same run, for a rigid TIP3P water box (PME) and the 27-benzene
cluster; ns/day, their ratio, and the integration's share of a step (the same runs with
the integration force groups set to a group that holds no force, so only the integration
remains).

Through pocl on a CPU the numbers are ratios only: a GPU's absolute speeds differ by orders
of magnitude. Usage (from the build tree's package):
    PYTHONPATH=build/python python3 benchmarks/python/opencl_speed.py [--waters 512] [--out docs/results/opencl_speed.csv]
"""
import argparse
import csv
import os
import sys
import time

import openmm
from openmm import unit

import mrattle

EMPTY_GROUP = 31  # no force is put in it


def seconds_per_step(context, integrator, steps):
    integrator.step(5)  # warm up (kernels compiled, neighbour lists built)
    context.getState(getEnergy=True)
    start = time.perf_counter()
    integrator.step(steps)
    context.getState(getPositions=True)  # waits for the device
    return (time.perf_counter() - start) / steps


def measure(model, make_integrator, precision, steps, integration_only):
    integrator = make_integrator()
    if integration_only:
        integrator.setIntegrationForceGroups({EMPTY_GROUP})
    platform = openmm.Platform.getPlatformByName('OpenCL')
    context = openmm.Context(model.system, integrator, platform, {'Precision': precision})
    context.setPositions(model.positions)
    context.setVelocitiesToTemperature(300 * unit.kelvin, 1)
    return seconds_per_step(context, integrator, steps)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--waters', type=int, default=512)
    parser.add_argument('--steps', type=int, default=200)
    parser.add_argument('--precision', default='mixed', choices=['single', 'mixed', 'double'])
    parser.add_argument('--out', default=None, help='CSV file for the table')
    args = parser.parse_args()
    if 'OpenCL' not in mrattle.DEVICE_PLATFORMS:
        sys.exit('no OpenCL kernels or no OpenCL platform: nothing to measure')
    dt = 0.002
    models = [
        ('%d TIP3P waters, PME' % args.waters,
         lambda: mrattle.models.waterBox(numMolecules=args.waters, cutoff=0.9 * unit.nanometers)),
        ('27 benzenes, vacuum', lambda: mrattle.models.benzeneCluster()),
    ]
    rows = []
    for name, build in models:
        model = build()
        has_constraints = model.system.getNumConstraints() > 0
        methods = [('M-RATTLE', lambda: mrattle.MRattleIntegrator(dt))]
        if has_constraints:
            methods.append(('Verlet + SETTLE', lambda: openmm.VerletIntegrator(dt)))
        for method, make in methods:
            for integration_only in (False, True):
                seconds = measure(model, make, args.precision, args.steps, integration_only)
                rows.append(dict(model=name, method=method, precision=args.precision,
                                 forces='excluded' if integration_only else 'included',
                                 ms_per_step=round(1e3 * seconds, 4),
                                 ns_per_day=round(dt * 1e-3 * 86400 / seconds, 3)))
                print('%-26s %-16s forces %-8s %9.3f ms/step %9.2f ns/day' % (
                    name, method, rows[-1]['forces'], rows[-1]['ms_per_step'], rows[-1]['ns_per_day']), flush=True)
        full = {r['method']: r['ms_per_step'] for r in rows if r['model'] == name and r['forces'] == 'included'}
        bare = {r['method']: r['ms_per_step'] for r in rows if r['model'] == name and r['forces'] == 'excluded'}
        print('  integration share of an M-RATTLE step: %.0f%%' % (100 * bare['M-RATTLE'] / full['M-RATTLE']))
        if 'Verlet + SETTLE' in full:
            print('  M-RATTLE / Verlet+SETTLE time per step: %.2f (forces included), %.2f (integration only)' % (
                full['M-RATTLE'] / full['Verlet + SETTLE'], bare['M-RATTLE'] / bare['Verlet + SETTLE']))
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, 'w', newline='') as out:
            writer = csv.DictWriter(out, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)


if __name__ == '__main__':
    main()
