"""RigidBodyMinimizer against OpenMM's LocalEnergyMinimizer: the comparison in docs/minimization.md.

For each System it writes the System, the positions and the bodies to a scratch folder and
runs the C++ program minimize_compare (which times both minimizers from the same start and
counts LocalEnergyMinimizer's iterations in a second, untimed run), then prints a Markdown
table and writes docs/results/minimization.csv.

    ./benchmarks/run.sh validate-minimization [--build build] [--platform CPU] [--quick] [--only NAME] [--repeats 3]
"""
import argparse
import csv
import io
import os
import subprocess
import sys
import tempfile

root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # three below


def cases(quick):
    from openmm import app
    import mrattle
    data = os.path.join(os.path.dirname(app.__file__), 'data')

    def model(build):
        m = build()
        return m.system, m.positions, None

    def pdbCase(name, forcefields, **options):
        pdb = app.PDBFile(os.path.join(data, name))
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


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--build', default=os.path.join(root, 'build'))
    parser.add_argument('--platform', default='CPU')
    parser.add_argument('--quick', action='store_true', help='the benzene cluster only')
    parser.add_argument('--only', help='the cases whose name contains this (no CSV is written)')
    parser.add_argument('--repeats', type=int, default=3, help='runs of each minimizer, alternated; the fastest counts')
    parser.add_argument('--out', default=os.path.join(root, 'docs', 'results', 'minimization.csv'))
    args = parser.parse_args(argv)
    sys.path.insert(0, os.path.join(args.build, 'python'))
    import openmm
    from openmm import unit
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
    fields = ['case', 'tolerance', 'minimizer', 'iterations', 'evaluations', 'energy_before', 'energy_after',
              'rms_force', 'max_shape_change', 'seconds', 'note']
    if not args.quick and not args.only:
        with open(args.out, 'w', newline='') as f:
            writer = csv.DictWriter(f, fieldnames=fields)
            writer.writeheader()
            writer.writerows(rows)
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

