#!/usr/bin/env python3
"""Rigid rings in a flexible molecule, run beside the flexible model: the four phenylalanine
rings of OpenMM's villin headpiece (openmm/app/data/test.pdb without its water and ions), amber14-all.xml,
no cutoff, constraints on bonds to hydrogen.

The rings (CG, CD1, HD1, CD2, HD2, CE1, HE1, CE2, HE2, CZ, HZ of each PHE) are chosen by atom
name with mrattle.rigidBodies(topology, system, {'PHE': [...]}) and integrated by
MRattleIntegrator; every other atom is free (velocity Verlet with RATTLE for its H-bond
constraints). The flexible model is the same System under OpenMM's VerletIntegrator. Both start
from the same minimised positions and velocities and run NVE; the script prints, for each, the
largest out-of-plane deviation of a ring atom, the total-energy drift and fluctuation, the
temperature and the rings' translational and rotational temperatures (rigid model), and the speed.

    python3 examples/rigid_ring.py --steps 2000
"""
import argparse
import os
import time

import numpy as np
import openmm
from openmm import app, unit

import mrattle

RING = ['CG', 'CD1', 'HD1', 'CD2', 'HD2', 'CE1', 'HE1', 'CE2', 'HE2', 'CZ', 'HZ']

parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
parser.add_argument('--steps', type=int, default=2000, help='steps of each model (default 2000)')
parser.add_argument('--step-size', type=float, default=1.0, help='fs (default 1)')
parser.add_argument('--temperature', type=float, default=300.0, help='K of the starting velocities (default 300)')
parser.add_argument('--platform', default='CPU', choices=mrattle.PLATFORMS)
arguments = parser.parse_args()
if arguments.steps <= 0 or arguments.step_size <= 0:
    parser.error('steps and step size must be positive')

pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), 'data', 'test.pdb'))
modeller = app.Modeller(pdb.topology, pdb.positions)
modeller.delete([residue for residue in modeller.topology.residues() if residue.name in ('HOH', 'Cl', 'Na')])
topology = modeller.topology
system = app.ForceField('amber14-all.xml').createSystem(topology, constraints=app.HBonds)
rings = mrattle.rigidBodies(topology, system, {'PHE': RING})
platform = openmm.Platform.getPlatformByName(arguments.platform)

# One start for both: minimised with the flexible model (the rings take that shape), 300 K velocities.
minimizer = openmm.Context(system, openmm.VerletIntegrator(0.001), platform)
minimizer.setPositions(modeller.positions)
openmm.LocalEnergyMinimizer.minimize(minimizer, 1.0, 500)
minimizer.setVelocitiesToTemperature(arguments.temperature*unit.kelvin, 1)
start = minimizer.getState(getPositions=True, getVelocities=True)


def planarity(x):
    """Largest distance of a ring atom from its ring's best plane (nm)."""
    worst = 0.0
    for ring in rings:
        p = x[ring] - x[ring].mean(axis=0)
        normal = np.linalg.svd(p)[2][2]
        worst = max(worst, float(np.max(np.abs(p.dot(normal)))))
    return worst


def run(name, integrator):
    context = openmm.Context(system, integrator, platform)
    context.setPositions(start.getPositions())
    context.setVelocities(start.getVelocities())
    energies, worst, temperatures, parts = [], 0.0, [], []
    chunks = 20
    began = time.time()
    for _ in range(chunks):
        integrator.step(max(1, arguments.steps//chunks))
        state = context.getState(getEnergy=True, getPositions=True)
        energies.append((state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(unit.kilojoules_per_mole))
        worst = max(worst, planarity(state.getPositions(asNumpy=True).value_in_unit(unit.nanometers)))
        temperatures.append(mrattle.kineticTemperature(context, state).value_in_unit(unit.kelvin))
        if isinstance(integrator, mrattle.RigidBodyIntegrator):
            parts.append((integrator.computeTranslationalTemperature().value_in_unit(unit.kelvin),
                          integrator.computeRotationalTemperature().value_in_unit(unit.kelvin)))
    seconds = time.time() - began
    steps = chunks*max(1, arguments.steps//chunks)
    drift = (energies[-1] - energies[0])
    print('%-34s %12.2e %12.3f %12.3f %8.1f %18s %8.1f' % (
        name, worst, drift, np.std(energies), np.mean(temperatures),
        '%.0f / %.0f' % tuple(np.mean(parts, axis=0)) if parts else '-',
        steps*arguments.step_size*1e-6/(seconds/86400)))


print('villin headpiece in vacuum: %d atoms, %d H-bond constraints, %d phenylalanine rings of %d atoms made rigid'
      % (system.getNumParticles(), system.getNumConstraints(), len(rings), len(RING)))
print('%d steps of %g fs each, NVE, %s platform' % (arguments.steps, arguments.step_size, arguments.platform))
print('%-34s %12s %12s %12s %8s %18s %8s' % ('model', 'ring out of', 'energy drift', 'energy std', 'T (K)',
                                              'rings T_tr / T_rot', 'ns/day'))
print('%-34s %12s %12s %12s' % ('', 'plane (nm)', '(kJ/mol)', '(kJ/mol)'))
flexible = openmm.VerletIntegrator(arguments.step_size*unit.femtoseconds)
run('flexible (VerletIntegrator)', flexible)
rigid = mrattle.MRattleIntegrator(arguments.step_size*unit.femtoseconds)
for ring in rings:
    rigid.addRigidBody(ring)
run('rigid rings (MRattleIntegrator)', rigid)
