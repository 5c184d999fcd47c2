#!/usr/bin/env python3
"""Rigid water from your own PDB file and force-field XML, integrated with M-RATTLE.

By default this uses the TIP3P water box that ships with OpenMM (openmm/app/data/tip3p.pdb,
895 molecules, PME) and tip3p.xml: M-RATTLE treats each water as one rigid body and ignores
the three constraints that ForceField puts in each (rigidWater=True). It equilibrates with an
Andersen thermostat, then runs NVE and prints the temperature and total-energy drift.

    python3 examples/water_box.py --pdb my_water.pdb --forcefield tip3p.xml --steps 1000
"""
import argparse
import os

import numpy as np
import openmm
from openmm import app, unit

import mrattle

parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
parser.add_argument('--pdb', default=os.path.join(os.path.dirname(app.__file__), 'data', 'tip3p.pdb'))
parser.add_argument('--forcefield', default='tip3p.xml', help='force-field XML (OpenMM name or path)')
parser.add_argument('--steps', type=int, default=500, help='NVE steps (default 500)')
parser.add_argument('--equilibration', type=int, default=200, help='thermostatted steps first (default 200)')
parser.add_argument('--step-size', type=float, default=2.0, help='fs (default 2)')
parser.add_argument('--temperature', type=float, default=300.0, help='K (default 300)')
parser.add_argument('--platform', default='CPU', choices=mrattle.PLATFORMS)
parser.add_argument('--output', default='output', help='output folder (default ./output)')
arguments = parser.parse_args()
os.makedirs(arguments.output, exist_ok=True)

pdb = app.PDBFile(arguments.pdb)
forceField = app.ForceField(arguments.forcefield)
system = forceField.createSystem(pdb.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometers,
                                 rigidWater=True)
thermostat = openmm.AndersenThermostat(arguments.temperature*unit.kelvin, 10/unit.picosecond)
system.addForce(thermostat)
integrator = mrattle.MRattleIntegrator(arguments.step_size*unit.femtoseconds)
simulation = app.Simulation(pdb.topology, system, integrator, openmm.Platform.getPlatformByName(arguments.platform))
simulation.context.setPositions(pdb.positions)
simulation.context.setVelocitiesToTemperature(arguments.temperature*unit.kelvin)
print('%d rigid molecules, %d degrees of freedom' % (integrator.getNumBodiesInEffect(),
                                                     integrator.getNumDegreesOfFreedom()))
simulation.step(arguments.equilibration)

# NVE: switch the thermostat off.
simulation.context.setParameter(openmm.AndersenThermostat.CollisionFrequency(), 0)
csvPath = os.path.join(arguments.output, 'water.csv')
interval = max(1, arguments.steps//50)
simulation.reporters.append(mrattle.StateDataReporter(csvPath, interval, step=True, time=True, totalEnergy=True,
                                                      temperature=True, speed=True))
simulation.step(arguments.steps)
data = np.atleast_2d(np.genfromtxt(csvPath, delimiter=','))
time_ps, total, temperature = data[:, 1], data[:, 2], data[:, 3]
drift = np.polyfit(time_ps, total, 1)[0] if len(time_ps) > 1 else float('nan')
print('NVE: temperature %.1f +- %.1f K, total energy drift %.3g kJ/mol/ps, log in %s'
      % (temperature.mean(), temperature.std(), drift, csvPath))
