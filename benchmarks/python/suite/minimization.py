"""RigidBodyMinimizer against OpenMM's LocalEnergyMinimizer (docs/minimization.md), two studies:

    ./benchmarks/run.sh validate-minimization [--platform CPU] [--quick] [--only NAME] [--repeats 3]
        each System minimized by both from one start by the C++ program minimize_compare (which times them
        and counts LocalEnergyMinimizer's iterations in a second, untimed run): a table, docs/results/minimization.csv
    ./benchmarks/run.sh validate-minimization-starts [--starts 8] [--sigma 0.005] [--tolerances 10 5 2 1]
        both minimizers' final energies on tip3p.pdb from many starts (where a minimizer stops depends on its
        path, and its path on round-off); LocalEnergyMinimizer's end read with the rigid minimizer's own test of
        the RMS generalized force: a table, docs/results/minimization_starts.csv and .png
"""
import argparse
import csv
import io
import math
import os
import subprocess
import tempfile

import numpy as np
import openmm
from openmm import app, unit

import mrattle
from . import common

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
DATA = os.path.join(os.path.dirname(app.__file__), 'data')


def parser(description, out):
    p = argparse.ArgumentParser(description=description)
    p.add_argument('--build', default=os.path.join(ROOT, 'build'))
    p.add_argument('--platform', default='CPU')
    p.add_argument('--out', default=os.path.join(ROOT, 'docs', 'results', out))
    return p


def cases(quick):
    def model(build):
        m = build()
        return m.system, m.positions, None

    def pdbCase(name, forcefields, **options):
        pdb = app.PDBFile(os.path.join(DATA, name))
        system = app.ForceField(*forcefields).createSystem(pdb.topology, nonbondedMethod=app.PME, rigidWater=True,
                                                           **options)
        bodies = mrattle.rigidBodies(pdb.topology, system, 'water') if 'constraints' in options else None
        return system, pdb.positions, bodies

    yield 'benzene cluster (vacuum)', 1.0, lambda: model(mrattle.models.benzeneCluster)
    yield 'benzene cluster (vacuum)', 10.0, lambda: model(mrattle.models.benzeneCluster)
    if quick:
        return
    yield 'liquid benzene (PME)', 1.0, lambda: model(mrattle.models.benzeneLiquid)
    yield 'liquid benzene (PME)', 10.0, lambda: model(mrattle.models.benzeneLiquid)
    yield 'tip3p.pdb (rigid water; PME)', 10.0, lambda: pdbCase('tip3p.pdb', ['tip3p.xml'])
    yield 'tip3p.pdb (rigid water; PME)', 5.0, lambda: pdbCase('tip3p.pdb', ['tip3p.xml'])
    yield 'test.pdb (rigid water; HBonds protein; PME)', 10.0, lambda: pdbCase(
        'test.pdb', ['amber14-all.xml', 'amber14/tip3p.xml'], constraints=app.HBonds)


def compare(argv=None):
    parser_ = parser('RigidBodyMinimizer against LocalEnergyMinimizer on several Systems', 'minimization.csv')
    parser_.add_argument('--quick', action='store_true', help='the benzene cluster only')
    parser_.add_argument('--only', help='the cases whose name contains this (no CSV is written)')
    parser_.add_argument('--repeats', type=int, default=3, help='runs of each minimizer, alternated; the fastest counts')
    args = parser_.parse_args(argv)
    program = os.path.join(args.build, 'benchmarks', 'cpp', 'minimize_compare')
    rows, notes = [], []
    for name, tolerance, build in cases(args.quick):
        if args.only and args.only not in name:
            continue
        system, positions, bodies = build()
        with tempfile.TemporaryDirectory() as scratch:
            with open(os.path.join(scratch, 'system.xml'), 'w') as f:
                f.write(openmm.XmlSerializer.serialize(system))
            with open(os.path.join(scratch, 'positions.txt'), 'w') as f:
                for p in positions.value_in_unit(unit.nanometer) if unit.is_quantity(positions) else positions:
                    f.write('%r %r %r\n' % (float(p[0]), float(p[1]), float(p[2])))
            with open(os.path.join(scratch, 'bodies.txt'), 'w') as f:
                for body in bodies or []:
                    f.write(' '.join(map(str, body)) + '\n')
            output = subprocess.run([program] + [os.path.join(scratch, n) for n in ('system.xml', 'positions.txt',
                                     'bodies.txt')] + [args.platform, repr(tolerance), name, str(args.repeats)],
                                    check=True, capture_output=True, text=True).stdout
        lines = output.splitlines()
        notes += [l[2:] + ' (tolerance %g)' % tolerance for l in lines if l.startswith('#')]
        for row in csv.DictReader(io.StringIO('\n'.join(l for l in lines if not l.startswith('#')))):
            row['tolerance'] = tolerance
            rows.append(row)
        print('\n'.join(lines[1:]), flush=True)
    if not args.quick and not args.only:
        common.write_csv(args.out, rows, ['case', 'tolerance', 'minimizer', 'iterations', 'evaluations', 'energy_before',
                                          'energy_after', 'rms_force', 'max_shape_change', 'seconds', 'note'])
    print('\nPlatform %s (Threads=1), OpenMM %s, fastest of %d alternated runs\n'
          % (args.platform, openmm.version.full_version, args.repeats))
    print('| System | tol. | minimizer | iterations | evaluations | energy before | energy after | RMS force | '
          'largest shape change (nm) | wall time (s) |')
    print('|---|---|---|---|---|---|---|---|---|---|')
    for r in rows:
        print('| %s | %g | %s | %s | %s | %.1f | %.1f | %.3g | %s | %.2f |' % (
            r['case'], r['tolerance'], r['minimizer'], r['iterations'], r['evaluations'], float(r['energy_before']),
            float(r['energy_after']), float(r['rms_force']), r['max_shape_change'], float(r['seconds'])))
    print()
    for note in notes:
        print('- ' + note)
    for r in rows:
        if r['note']:
            print('- %s, %s: %s' % (r['case'], r['minimizer'], r['note']))



def meanAndError(values):
    n = len(values)
    mean = sum(values) / n
    if n < 2:
        return mean, float('nan')
    variance = sum((v - mean) ** 2 for v in values) / (n - 1)
    return mean, math.sqrt(variance / n)


def starts(argv=None):
    parser_ = parser('Both minimizers on tip3p.pdb from many starts', 'minimization_starts.csv')
    parser_.add_argument('--threads', default='2', help='CPU threads (only round-off depends on it)')
    parser_.add_argument('--starts', type=int, default=8)
    parser_.add_argument('--sigma', type=float, default=0.005, help='nm, per component of each water\'s translation')
    parser_.add_argument('--tolerances', type=float, nargs='+', default=[10.0, 5.0, 2.0, 1.0])
    args = parser_.parse_args(argv)

    pdb = app.PDBFile(os.path.join(DATA, 'tip3p.pdb'))
    system = app.ForceField('tip3p.xml').createSystem(pdb.topology, nonbondedMethod=app.PME, rigidWater=True)
    platform = openmm.Platform.getPlatformByName(args.platform)
    properties = {'Threads': args.threads} if platform.getName() == 'CPU' else {}
    rigid = openmm.Context(system, mrattle.MRattleIntegrator(1 * unit.femtoseconds), platform, properties)
    settle = openmm.Context(system, openmm.VerletIntegrator(1 * unit.femtoseconds), platform, properties)
    rigid.setPositions(pdb.positions)
    exact = rigid.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    waters = [[atom.index for atom in residue.atoms()] for residue in pdb.topology.residues()]
    kJ = unit.kilojoules_per_mole

    rows = []
    for start in range(args.starts):
        positions = np.array(exact)
        if start > 0:
            rng = np.random.default_rng(start)
            for water in waters:
                positions[water] += rng.normal(0.0, args.sigma, 3)
        for tolerance in args.tolerances:
            rigid.setPositions(positions)
            report = mrattle.minimizeEnergy(rigid, tolerance * kJ / unit.nanometer)
            settle.setPositions(positions)
            openmm.LocalEnergyMinimizer.minimize(settle, tolerance)
            # Read LocalEnergyMinimizer's end with the rigid test: no iteration at a huge tolerance.
            rigid.setPositions(settle.getState(getPositions=True).getPositions())
            atOpenMMsEnd = mrattle.minimizeEnergy(rigid, 1e9 * kJ / unit.nanometer)
            rigid.setPositions(settle.getState(getPositions=True).getPositions())
            passes = mrattle.minimizeEnergy(rigid, tolerance * kJ / unit.nanometer).iterations == 0
            row = dict(start=start, tolerance=tolerance, rigid_iterations=report.iterations,
                       rigid_energy=report.finalEnergy, rigid_rms_force=report.rmsForce,
                       openmm_energy=settle.getState(getEnergy=True).getPotentialEnergy().value_in_unit(kJ),
                       openmm_rms_force=atOpenMMsEnd.rmsForce, openmm_end_passes_rigid_test=passes)
            row['gap'] = row['rigid_energy'] - row['openmm_energy']
            # The rigid minimizer stopped at the RMS generalized force LocalEnergyMinimizer reached.
            rigid.setPositions(positions)
            matched = mrattle.minimizeEnergy(rigid, row['openmm_rms_force'] * kJ / unit.nanometer)
            row['matched_rigid_energy'] = matched.finalEnergy
            row['matched_gap'] = matched.finalEnergy - row['openmm_energy']
            rows.append(row)
            print('start %d tolerance %g: rigid %.1f (%d iterations, rms %.2f), LocalEnergyMinimizer %.1f (rms %.2f%s), '
                  'gap %.1f; rigid to that rms %.1f, gap %.1f'
                  % (start, tolerance, row['rigid_energy'], row['rigid_iterations'], row['rigid_rms_force'],
                     row['openmm_energy'], row['openmm_rms_force'], ', passes' if passes else '', row['gap'],
                     row['matched_rigid_energy'], row['matched_gap']), flush=True)

    common.write_csv(args.out, rows)

    print('\n%d starts (sigma %g nm), %s platform, OpenMM %s; mean +- standard error over the starts\n'
          % (args.starts, args.sigma, platform.getName(), openmm.version.full_version))
    print('| tolerance | rigid final energy | rigid iterations | LocalEnergyMinimizer final energy | '
          'rigid - LocalEnergyMinimizer | starts where rigid is lower | rigid RMS force | '
          'LocalEnergyMinimizer RMS force (rigid test) | rigid to that RMS force - LocalEnergyMinimizer |')
    print('|---|---|---|---|---|---|---|---|---|')
    summary = []
    for tolerance in args.tolerances:
        mine = [r for r in rows if r['tolerance'] == tolerance]
        stats = {key: meanAndError([r[key] for r in mine])
                 for key in ('rigid_energy', 'rigid_iterations', 'openmm_energy', 'gap', 'rigid_rms_force',
                             'openmm_rms_force', 'matched_gap')}
        lower = sum(r['gap'] < 0 for r in mine)
        summary.append((tolerance, stats))
        print('| %g | %.1f +- %.1f | %.0f +- %.0f | %.1f +- %.1f | %.1f +- %.1f | %d of %d | %.2f | %.2f +- %.2f | '
              '%.1f +- %.1f |' % (tolerance, *stats['rigid_energy'], *stats['rigid_iterations'],
                                  *stats['openmm_energy'], *stats['gap'], lower, len(mine),
                                  stats['rigid_rms_force'][0], *stats['openmm_rms_force'], *stats['matched_gap']))

    plt = common.pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.2))
    tolerances = [t for t, _ in summary]
    for key, label in (('rigid_energy', 'RigidBodyMinimizer'), ('openmm_energy', 'LocalEnergyMinimizer (SETTLE)')):
        ax.errorbar(tolerances, [s[key][0] for _, s in summary], yerr=[s[key][1] for _, s in summary],
                    fmt='o-', capsize=3, label=label)
    ax.set_xscale('log')
    ax.set_xlabel('tolerance (kJ/mol/nm)')
    ax.set_ylabel('final potential energy (kJ/mol)')
    ax.set_title('tip3p.pdb, %d starts: mean +- standard error' % args.starts)
    ax.legend()
    common.save_figure(fig, args.out[:-len('.csv')] + '.png')

