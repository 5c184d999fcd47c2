#!/usr/bin/env python3
"""Rigid TIP3P water at constant temperature and pressure: MRattleLangevinIntegrator with a
MonteCarloBarostat, on OpenMM's own water box (openmm/app/data/tip3p.pdb, 895 molecules,
amber14/tip3p.xml, PME).

Prints the progress and time left (stderr), writes the temperature (rigid-body degrees of
freedom), density and energies to a CSV file, and plots temperature and density against time.

    python3 examples/langevin_water.py --steps 25000 --output output
"""
import argparse
import os
import sys

import numpy as np
import openmm
from openmm import app, unit

import mrattle

parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
parser.add_argument('--pdb', default=os.path.join(os.path.dirname(app.__file__), 'data', 'tip3p.pdb'))
parser.add_argument('--steps', type=int, default=5000, help='steps (default 5000 = 10 ps)')
parser.add_argument('--step-size', type=float, default=2.0, help='fs (default 2)')
parser.add_argument('--temperature', type=float, default=300.0, help='K (default 300)')
parser.add_argument('--pressure', type=float, default=1.0, help='bar (default 1)')
parser.add_argument('--friction', type=float, default=1.0, help='1/ps (default 1)')
parser.add_argument('--report-interval', type=int, default=100, help='steps between reports (default 100)')
parser.add_argument('--platform', default='CPU', choices=mrattle.PLATFORMS)
parser.add_argument('--output', default='output', help='output folder (default ./output)')
arguments = parser.parse_args()
if arguments.steps <= 0 or arguments.report_interval <= 0 or arguments.step_size <= 0:
    parser.error('steps, report interval and step size must be positive')
os.makedirs(arguments.output, exist_ok=True)

pdb = app.PDBFile(arguments.pdb)
forceField = app.ForceField('amber14/tip3p.xml')
system = forceField.createSystem(pdb.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometers,
                                 rigidWater=True)
system.addForce(openmm.MonteCarloBarostat(arguments.pressure*unit.bar, arguments.temperature*unit.kelvin))
integrator = mrattle.MRattleLangevinIntegrator(arguments.temperature*unit.kelvin,
                                               arguments.friction/unit.picosecond, arguments.step_size*unit.femtoseconds)
simulation = app.Simulation(pdb.topology, system, integrator, openmm.Platform.getPlatformByName(arguments.platform))
simulation.context.setPositions(pdb.positions)  # each water takes exact TIP3P geometry
simulation.context.setVelocitiesToTemperature(arguments.temperature*unit.kelvin)
print('%d rigid waters, %d degrees of freedom, %s platform' % (integrator.getNumBodiesInEffect(),
                                                               integrator.getNumDegreesOfFreedom(), arguments.platform))

csvPath = os.path.join(arguments.output, 'langevin_water.csv')
simulation.reporters.append(mrattle.StateDataReporter(csvPath, arguments.report_interval, step=True, time=True,
                                                      potentialEnergy=True, temperature=True, density=True, speed=True))
# Progress and time left on stderr: OpenMM's own reporter.
simulation.reporters.append(app.StateDataReporter(sys.stderr, max(1, arguments.steps//10), progress=True,
                                                  remainingTime=True, speed=True, totalSteps=arguments.steps))
simulation.step(arguments.steps)

data = np.atleast_2d(np.genfromtxt(csvPath, delimiter=',', skip_header=1))
time_ps, potential, temperature, density = data[:, 1], data[:, 2], data[:, 3], data[:, 4]
half = len(time_ps)//2
print('second half: temperature %.1f K (target %.1f), density %.4f g/mL, potential energy %.1f kJ/mol; log in %s'
      % (temperature[half:].mean(), arguments.temperature, density[half:].mean(), potential[half:].mean(), csvPath))

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
figure, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
top.plot(time_ps, temperature, lw=1)
top.axhline(arguments.temperature, color='k', ls='--', lw=1, label='bath')
top.set_ylabel('temperature (K)\n(rigid-body DOF)')
top.legend()
bottom.plot(time_ps, density, lw=1, color='tab:green')
bottom.set_ylabel('density (g/mL)')
bottom.set_xlabel('time (ps)')
top.set_title('Rigid TIP3P water, MRattleLangevinIntegrator + MonteCarloBarostat (%g bar)' % arguments.pressure,
              fontsize=10)
figure.tight_layout()
plotPath = os.path.join(arguments.output, 'langevin_water.png')
figure.savefig(plotPath, dpi=100)
print('plot in %s' % plotPath)
