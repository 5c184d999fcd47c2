"""Final energies of RigidBodyMinimizer and LocalEnergyMinimizer on tip3p.pdb from many starts.

Where a minimizer stops depends on its path, and its path on round-off, so one start says
little about a difference of final energies. Each start here is OpenMM's tip3p.pdb with the
rigid integrator's exact water shapes, every water then translated by a random vector
(normal, `--sigma` nm per component; start 0 is not moved). From each start both
minimizers run at each tolerance: `mrattle.minimizeEnergy` with `MRattleIntegrator`, and
`LocalEnergyMinimizer` with `VerletIntegrator` (SETTLE), as a stock script would. The RMS
generalized force of `LocalEnergyMinimizer`'s end (the force projected on rigid motion of
exact waters) is read with the rigid minimizer's own test, which it passes when that
minimizer, started there, makes no iteration.

Prints a Markdown table (means with standard errors over the starts), writes the rows to
docs/results/minimization_starts.csv and a plot to docs/results/minimization_starts.png.

    ./benchmarks/run.sh validate-minimization-starts [--build build] [--starts 8] [--tolerances 10 5 2 1]
"""
import argparse
import csv
import math
import os
import sys

from . import common

root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # three below


def meanAndError(values):
    n = len(values)
    mean = sum(values) / n
    if n < 2:
        return mean, float('nan')
    variance = sum((v - mean) ** 2 for v in values) / (n - 1)
    return mean, math.sqrt(variance / n)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--build', default=os.path.join(root, 'build'))
    parser.add_argument('--platform', default='CPU')
    parser.add_argument('--threads', default='2', help='CPU threads (only round-off depends on it)')
    parser.add_argument('--starts', type=int, default=8)
    parser.add_argument('--sigma', type=float, default=0.005, help='nm, per component of each water\'s translation')
    parser.add_argument('--tolerances', type=float, nargs='+', default=[10.0, 5.0, 2.0, 1.0])
    parser.add_argument('--out', default=os.path.join(root, 'docs', 'results', 'minimization_starts.csv'))
    parser.add_argument('--plot', default=os.path.join(root, 'docs', 'results', 'minimization_starts.png'))
    args = parser.parse_args(argv)
    sys.path.insert(0, os.path.join(args.build, 'python'))
    import numpy as np
    import openmm
    from openmm import app, unit
    import mrattle

    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), 'data', 'tip3p.pdb'))
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

    with open(args.out, 'w', newline='') as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)

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
    fig.tight_layout()
    fig.savefig(args.plot, dpi=110)
    plt.close(fig)

