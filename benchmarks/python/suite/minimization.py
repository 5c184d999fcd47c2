"""RigidBodyMinimizer against OpenMM's LocalEnergyMinimizer (docs/minimization.md), two studies:

    ./benchmarks/run.sh validate-minimization [--platform CPU] [--quick] [--only NAME] [--repeats 3]
        each System minimized by both from one start, timed; LocalEnergyMinimizer's iterations counted in a second,
        untimed run by the C++ program minimizer_iterations: a table, docs/results/minimization.csv
    ./benchmarks/run.sh validate-minimization-starts [--starts 8] [--sigma 0.005] [--tolerances 10 5 2 1]
        both minimizers' final energies on tip3p.pdb from many starts (where a minimizer stops depends on its
        path, and its path on round-off); LocalEnergyMinimizer's end read with the rigid minimizer's own test of
        the RMS generalized force: a table, docs/results/minimization_starts.csv and .png
"""
import argparse
import math
import os
import subprocess
import tempfile
import time

import numpy as np
import openmm
from openmm import app, unit

import mrattle
from . import common

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
DATA = os.path.join(os.path.dirname(app.__file__), 'data')


def nm(state):
    return state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)


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


def rms_generalized_force(system, x, f, bodies):
    """RMS over particles of the force projected on the allowed motion: each body's rigid motion (unit masses),
    the constraints' tangent space for the other particles (A A^T l = A f by conjugate gradients, A's row k
    the unit vector of constraint k on its two particles)."""
    n, masses = len(x), common.masses(system)
    free = np.ones(n, bool)
    total = 0.0
    for body in bodies:
        free[body] = False
        r, forces = x[body] - x[body].mean(0), f[body]
        values, vectors = np.linalg.eigh((r * r).sum() * np.eye(3) - r.T @ r)
        kept = values > 1e-9 * values[2]
        total += np.sum((vectors[:, kept].T @ np.cross(r, forces).sum(0)) ** 2 / values[kept])
        total += forces.sum(0) @ forces.sum(0) / len(body)
    free &= masses != 0
    pairs = np.array([c[:2] for c in map(system.getConstraintParameters, range(system.getNumConstraints()))
                      if free[c[0]] and free[c[1]]], int).reshape(-1, 2)
    projected = np.where(free[:, None], f, 0.0)
    u = x[pairs[:, 1]] - x[pairs[:, 0]]
    u /= np.linalg.norm(u, axis=1)[:, None]
    along = lambda g: np.einsum('ij,ij->i', u, g[pairs[:, 1]] - g[pairs[:, 0]])  # noqa: E731  (A g)

    def spread(l):  # A^T l
        out = np.zeros((n, 3))
        np.add.at(out, pairs[:, 0], -u * l[:, None])
        np.add.at(out, pairs[:, 1], u * l[:, None])
        return out
    b = along(projected)
    l, residual, direction, rr = np.zeros(len(pairs)), b.copy(), b.copy(), b @ b
    for _ in range(1000):
        if rr <= 1e-28 * max(b @ b, 1e-300):
            break
        q = along(spread(direction))
        alpha = rr / (direction @ q)
        l, residual = l + alpha * direction, residual - alpha * q
        rr, previous = residual @ residual, rr
        direction = residual + rr / previous * direction
    projected -= spread(l)
    return math.sqrt((total + (projected ** 2).sum()) / n)


def shape_change(a, b, bodies):
    """The largest change of a distance within one body."""
    d = lambda x, body: np.linalg.norm(x[body][:, None] - x[body], axis=2)  # noqa: E731
    return max((np.abs(d(a, body) - d(b, body)).max() for body in bodies), default=0.0)


def compare_one(name, tolerance, system, positions, bodies, platform, repeats, program):
    """Both minimizers from the rigid integrator's exact shapes, each run `repeats` times alternated with the
    other, the fastest run counting; LocalEnergyMinimizer's iterations counted by `program` in a second run."""
    integrator = mrattle.MRattleIntegrator(0.001)
    for body in bodies or []:
        integrator.addRigidBody(body)
    rigid = common.context(system, integrator, positions, platform_name=platform, threads=1)
    start = nm(rigid.getState(getPositions=True))
    bodies = [list(b) for b in integrator.getBodiesInEffect()]
    verlet = openmm.VerletIntegrator(0.001)
    verlet.setConstraintTolerance(integrator.getConstraintTolerance())
    flexible = common.context(system, verlet, start, platform_name=platform, threads=1)
    seconds = {'RigidBodyMinimizer': [], 'LocalEnergyMinimizer': []}
    for _ in range(repeats):
        rigid.setPositions(start)
        began = time.perf_counter()
        report = mrattle.minimizeEnergy(rigid, tolerance)
        seconds['RigidBodyMinimizer'].append(time.perf_counter() - began)
        flexible.setPositions(start)
        before = flexible.getState(getEnergy=True).getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)
        began = time.perf_counter()
        openmm.LocalEnergyMinimizer.minimize(flexible, tolerance)
        seconds['LocalEnergyMinimizer'].append(time.perf_counter() - began)
    with tempfile.TemporaryDirectory() as scratch:
        with open(os.path.join(scratch, 'system.xml'), 'w') as f:
            f.write(openmm.XmlSerializer.serialize(system))
        np.savetxt(os.path.join(scratch, 'positions.txt'), start, '%r')
        counted = subprocess.run([program, os.path.join(scratch, 'system.xml'), os.path.join(scratch, 'positions.txt'),
                                  platform, repr(tolerance), repr(integrator.getConstraintTolerance())],
                                 check=True, capture_output=True, text=True).stdout.split()
    rows = []
    for minimizer, context, energy_before, held in (('RigidBodyMinimizer', rigid, report.initialEnergy, bodies),
                                                    ('LocalEnergyMinimizer', flexible, before, [])):
        end = context.getState(getPositions=True, getForces=True, getEnergy=True)
        after = end.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)
        forces = end.getForces(asNumpy=True).value_in_unit(unit.kilojoule_per_mole / unit.nanometer)
        rows.append(dict(case=name, tolerance=tolerance, minimizer=minimizer, energy_before='%.6f' % energy_before,
                         energy_after='%.6f' % after, rms_force='%.4f' % rms_generalized_force(system, nm(end), forces, held),
                         max_shape_change='%.3g' % shape_change(start, nm(end), bodies),
                         seconds='%.3f' % min(seconds[minimizer]), iterations=report.iterations,
                         evaluations=report.evaluations, note=''))
    same = abs(float(counted[2]) - after) <= 1e-9 * abs(after) + 1e-9
    rows[1].update(iterations=int(counted[0]), evaluations=int(counted[1]), note=(
        'iterations counted in a second run that ended at the same energy' if same else
        'iterations counted in a second run that ended ELSEWHERE: count not valid'))
    return rows


def compare(argv=None):
    parser_ = parser('RigidBodyMinimizer against LocalEnergyMinimizer on several Systems', 'minimization.csv')
    parser_.add_argument('--quick', action='store_true', help='the benzene cluster only')
    parser_.add_argument('--only', help='the cases whose name contains this (no CSV is written)')
    parser_.add_argument('--repeats', type=int, default=3, help='runs of each minimizer, alternated; the fastest counts')
    args = parser_.parse_args(argv)
    program = os.path.join(args.build, 'benchmarks', 'cpp', 'minimizer_iterations')
    rows, notes = [], []
    for name, tolerance, build in cases(args.quick):
        if args.only and args.only not in name:
            continue
        mine, theirs = compare_one(name, tolerance, *build(), args.platform, max(1, args.repeats), program)
        rows += [mine, theirs]
        if mine['iterations'] > 0 and theirs['iterations'] > 0:
            per = lambda key: (float(mine['seconds']) / mine[key]) / (float(theirs['seconds']) / theirs[key])  # noqa: E731
            notes.append('%s: cost per iteration, RigidBodyMinimizer / LocalEnergyMinimizer = %.3f; per evaluation '
                         '%.3f (tolerance %g)' % (name, per('iterations'), per('evaluations'), tolerance))
        print(mine, theirs, sep='\n', flush=True)
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
    print('\n' + ''.join('- %s\n' % n for n in notes + ['%s, %s: %s' % (r['case'], r['minimizer'], r['note'])
                                                     for r in rows if r['note']]))


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
    exact = nm(rigid.getState(getPositions=True))
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
            print(row, flush=True)
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
        stats = {key: (np.mean([r[key] for r in mine]), np.std([r[key] for r in mine], ddof=1) / math.sqrt(len(mine)))
                 for key in ('rigid_energy', 'rigid_iterations', 'openmm_energy', 'gap', 'rigid_rms_force',
                             'openmm_rms_force', 'matched_gap')}
        lower = sum(r['gap'] < 0 for r in mine)
        summary.append((tolerance, stats))
        print('| %g | %.1f +- %.1f | %.0f +- %.0f | %.1f +- %.1f | %.1f +- %.1f | %d of %d | %.2f | %.2f +- %.2f | '
              '%.1f +- %.1f |' % (tolerance, *stats['rigid_energy'], *stats['rigid_iterations'],
                                  *stats['openmm_energy'], *stats['gap'], lower, len(mine),
                                  stats['rigid_rms_force'][0], *stats['openmm_rms_force'], *stats['matched_gap']))

    fig, (ax,) = common.panels(1, 6)
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

