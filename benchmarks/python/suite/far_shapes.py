"""Water shapes far from the origin on a device platform (issue 31, item 4): OpenMM's
tip3p.pdb (895 rigid TIP3P waters, PME, cutoff 0.9 nm) moved 30 nm from the origin along
each axis, NVE at 2 fs from 300 K velocities, M-RATTLE against OpenMM's VerletIntegrator
with SETTLE in the same run; the largest O-H and H-H length errors over all waters,
sampled every --every steps, in single and mixed precision.

SETTLE rebuilds each water from its triangle every step; M-RATTLE rebuilds each body from
its reference geometry and orientation, so neither error should grow with the run. The
test suite's cheap form of this (27 waters, no forces) is
DevicePlatform.WaterShapesStayExactFarFromTheOriginLikeSettle. Usage:
    ./benchmarks/run.sh validate-far-shapes [--steps 50000] [--every 5000] [--precisions single,mixed] [--out FILE.csv]
"""
import argparse
import csv
import math
import os
import sys
import time

import openmm
from openmm import app, unit

import mrattle

OH, HH = 0.09572, 0.09572 * 2 * math.sin(math.radians(104.52) / 2)  # TIP3P, nm
SHIFT = 30.0  # nm, along each axis


def largest_errors(positions, waters):
    x = positions.value_in_unit(unit.nanometers)
    oh = hh = 0.0
    for o, h1, h2 in waters:
        d = [x[o][i] - x[h1][i] for i in range(3)]
        e = [x[o][i] - x[h2][i] for i in range(3)]
        f = [x[h1][i] - x[h2][i] for i in range(3)]
        oh = max(oh, abs(math.sqrt(sum(c * c for c in d)) - OH), abs(math.sqrt(sum(c * c for c in e)) - OH))
        hh = max(hh, abs(math.sqrt(sum(c * c for c in f)) - HH))
    return oh, hh


def exact_start(pdb, system):
    """tip3p.pdb moved SHIFT nm along each axis, its waters made exact (Reference, double)."""
    context = openmm.Context(system, openmm.VerletIntegrator(0.002), openmm.Platform.getPlatformByName('Reference'))
    context.setPositions([p + openmm.Vec3(SHIFT, SHIFT, SHIFT) for p in pdb.positions.value_in_unit(unit.nanometers)])
    context.applyConstraints(1e-12)
    return context.getState(getPositions=True).getPositions()


def run(method, precision, start_positions, system, waters, steps, every):
    integrator = (mrattle.MRattleIntegrator(0.002) if method == 'M-RATTLE' else openmm.VerletIntegrator(0.002))
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName('OpenCL'),
                             {'Precision': precision})
    context.setPositions(start_positions)
    context.setVelocitiesToTemperature(300 * unit.kelvin, 7)
    rows, start = [], time.perf_counter()
    oh, hh = largest_errors(context.getState(getPositions=True).getPositions(), waters)
    rows.append(dict(method=method, precision=precision, step=0, largest_oh_error_nm=oh, largest_hh_error_nm=hh))
    done = 0
    while done < steps:
        integrator.step(every)
        done += every
        state = context.getState(getPositions=True, getEnergy=True)
        oh, hh = largest_errors(state.getPositions(), waters)
        energy = (state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(unit.kilojoules_per_mole)
        rows.append(dict(method=method, precision=precision, step=done, largest_oh_error_nm=oh,
                         largest_hh_error_nm=hh, total_energy_kj_mol=energy))
        print('%-9s %-6s step %6d  O-H %.2e nm  H-H %.2e nm  E %.1f kJ/mol  (%.0f s)' % (
            method, precision, done, oh, hh, energy, time.perf_counter() - start), flush=True)
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--steps', type=int, default=50000)
    parser.add_argument('--every', type=int, default=5000)
    parser.add_argument('--precisions', default='single,mixed')
    parser.add_argument('--out', default=None, help='CSV file for the samples')
    args = parser.parse_args(argv)
    if 'OpenCL' not in mrattle.DEVICE_PLATFORMS:
        sys.exit('no OpenCL kernels or no OpenCL platform: nothing to measure')
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), 'data', 'tip3p.pdb'))
    forcefield = app.ForceField('tip3p.xml')
    system = forcefield.createSystem(pdb.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9 * unit.nanometers,
                                     constraints=None, rigidWater=True)
    waters = [tuple(atom.index for atom in residue.atoms()) for residue in pdb.topology.residues()]
    start_positions = exact_start(pdb, system)
    rows = []
    for precision in args.precisions.split(','):
        for method in ('Verlet+SETTLE', 'M-RATTLE'):
            rows += run(method, precision, start_positions, system, waters, args.steps, args.every)
    # Step 0 is the positions as uploaded (float storage at 31-32 nm); once the atoms are
    # first reordered OpenMM keeps them wrapped into the box on the device, adding the cell
    # offsets back in double when a State is made: the rows after step 0 are the integration's.
    print('\nlargest error over the steps after 0 (nm):')
    for precision in args.precisions.split(','):
        for method in ('Verlet+SETTLE', 'M-RATTLE'):
            mine = [r for r in rows if r['method'] == method and r['precision'] == precision and r['step'] > 0]
            print('  %-6s %-14s O-H %.2e  H-H %.2e' % (precision, method, max(r['largest_oh_error_nm'] for r in mine),
                                                      max(r['largest_hh_error_nm'] for r in mine)))
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, 'w', newline='') as out:
            writer = csv.DictWriter(out, fieldnames=list(rows[-1]))
            writer.writeheader()
            writer.writerows(rows)

