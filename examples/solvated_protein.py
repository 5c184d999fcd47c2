#!/usr/bin/env python3
"""A solvated protein with rigid water and a flexible protein: OpenMM's villin headpiece in
2761 TIP3P waters (openmm/app/data/test.pdb), amber14-all.xml + amber14/tip3p.xml, PME,
constraints on bonds to hydrogen in the protein.

The waters are declared rigid bodies (mrattle.declareRigidBodies); the protein's atoms are
free particles, integrated like LangevinMiddleIntegrator with RATTLE for their H-bond
constraints. Prints the temperature (rigid-body degrees of freedom) and how well the
H-bond constraints and the waters' geometry hold; the progress and time left go to stderr.

    python3 examples/solvated_protein.py --steps 1000
"""
import argparse
import os
import sys

import numpy as np
import openmm
from openmm import app, unit

import mrattle

parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
parser.add_argument('--steps', type=int, default=500, help='steps (default 500)')
parser.add_argument('--step-size', type=float, default=2.0, help='fs (default 2)')
parser.add_argument('--temperature', type=float, default=300.0, help='K (default 300)')
parser.add_argument('--platform', default='CPU', choices=mrattle.PLATFORMS)
arguments = parser.parse_args()
if arguments.steps <= 0 or arguments.step_size <= 0:
    parser.error('steps and step size must be positive')

pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), 'data', 'test.pdb'))
forceField = app.ForceField('amber14-all.xml', 'amber14/tip3p.xml')
system = forceField.createSystem(pdb.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometers,
                                 constraints=app.HBonds, rigidWater=True)
integrator = mrattle.MRattleLangevinIntegrator(arguments.temperature*unit.kelvin, 1/unit.picosecond,
                                               arguments.step_size*unit.femtoseconds)
numWaters = mrattle.declareRigidBodies(integrator, pdb.topology, system, 'water')
simulation = app.Simulation(pdb.topology, system, integrator, openmm.Platform.getPlatformByName(arguments.platform))
simulation.context.setPositions(pdb.positions)  # each water takes exact TIP3P geometry
simulation.context.setVelocitiesToTemperature(arguments.temperature*unit.kelvin)
print('%d rigid waters, %d free (protein) atoms, %d H-bond constraints among them, %d degrees of freedom'
      % (numWaters, len(integrator.getFreeParticles()),
         sum(1 for i in range(system.getNumConstraints())
             if system.getConstraintParameters(i)[0] in set(integrator.getFreeParticles())),
         integrator.getNumDegreesOfFreedom()))
chunk = max(1, arguments.steps//10)
# Progress and time left on stderr: OpenMM's own reporter.
simulation.reporters.append(app.StateDataReporter(sys.stderr, chunk, progress=True, remainingTime=True, speed=True,
                                                  totalSteps=10*chunk))
temperatures = []
for block in range(10):
    simulation.step(chunk)
    temperatures.append(integrator.computeSystemTemperature().value_in_unit(unit.kelvin))

x = simulation.context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
free = set(integrator.getFreeParticles())
worstConstraint = 0.0
for i in range(system.getNumConstraints()):
    p1, p2, distance = system.getConstraintParameters(i)
    if p1 in free:
        worstConstraint = max(worstConstraint, abs(np.linalg.norm(x[p1] - x[p2]) - distance.value_in_unit(unit.nanometers)))
worstWater = max(abs(np.linalg.norm(x[b[0]] - x[b[1]]) - 0.09572) for b in integrator.getBodiesInEffect())
print('temperature %.1f K (last half), largest H-bond constraint error %.2g nm, largest water O-H error %.2g nm'
      % (np.mean(temperatures[5:]), worstConstraint, worstWater))
