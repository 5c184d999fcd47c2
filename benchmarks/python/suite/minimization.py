"""RigidBodyMinimizer against OpenMM's LocalEnergyMinimizer (docs/minimization.md):

    ./benchmarks/run.sh validate-minimization [--platform CPU] [--quick] [--only NAME] [--repeats 3]
        each System minimized by both from one start, timed; LocalEnergyMinimizer's iterations counted in a second,
        untimed run by the C++ program minimizer_iterations: a table, docs/results/minimization.csv
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
    parser_ = argparse.ArgumentParser(description='RigidBodyMinimizer against LocalEnergyMinimizer on several Systems')
    parser_.add_argument('--build', default=os.path.join(ROOT, 'build'))
    parser_.add_argument('--platform', default='CPU')
    parser_.add_argument('--out', default=os.path.join(ROOT, 'docs', 'results', 'minimization.csv'))
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
