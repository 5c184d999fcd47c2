#!/usr/bin/env python3
"""Liquid benzene at constant pressure with rigid molecules (M-RATTLE + Monte Carlo barostat).

A periodic box of rigid benzene (PME electrostatics, cut-off Lennard-Jones with long-range
correction), Andersen thermostat and Monte Carlo barostat: the step calls
updateContextState(), so both act. Prints the density as it relaxes (experiment: 0.874
g/mL at 298 K) and writes a CSV log and DCD trajectory.

    python3 examples/liquid_benzene.py --molecules 64 --steps 2000
"""
import argparse
import os

import openmm
from openmm import app, unit

import mrattle

parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
parser.add_argument('--molecules', type=int, default=64, help='number of molecules (default 64)')
parser.add_argument('--cutoff', type=float, default=0.9, help='nm, at most half the box edge (default 0.9)')
parser.add_argument('--steps', type=int, default=2000, help='number of steps (default 2000)')
parser.add_argument('--step-size', type=float, default=2.0, help='fs (default 2)')
parser.add_argument('--temperature', type=float, default=298.0, help='K (default 298)')
parser.add_argument('--pressure', type=float, default=1.0, help='bar (default 1)')
parser.add_argument('--platform', default='CPU', choices=mrattle.PLATFORMS)
parser.add_argument('--output', default='output', help='output folder (default ./output)')
arguments = parser.parse_args()
os.makedirs(arguments.output, exist_ok=True)

temperature = arguments.temperature*unit.kelvin
model = mrattle.models.benzeneLiquid(numMolecules=arguments.molecules, cutoff=arguments.cutoff*unit.nanometers)
# Bonds, angles, torsions and pairs inside a molecule cannot move a rigid molecule: drop them.
system = mrattle.removeIntraBodyInteractions(model.system, model.positions, 'molecules')
system.addForce(openmm.AndersenThermostat(temperature, 5/unit.picosecond))
system.addForce(openmm.MonteCarloBarostat(arguments.pressure*unit.bar, temperature, 25))
integrator = mrattle.MRattleIntegrator(arguments.step_size*unit.femtoseconds)
simulation = app.Simulation(model.topology, system, integrator, openmm.Platform.getPlatformByName(arguments.platform))
simulation.context.setPositions(model.positions)
simulation.context.setVelocitiesToTemperature(temperature)

with open(os.path.join(arguments.output, 'liquid_benzene.pdb'), 'w') as pdb:
    app.PDBFile.writeFile(model.topology, model.positions, pdb)
interval = max(1, arguments.steps//20)
simulation.reporters.append(app.DCDReporter(os.path.join(arguments.output, 'liquid_benzene.dcd'), interval))
simulation.reporters.append(mrattle.StateDataReporter(os.path.join(arguments.output, 'liquid_benzene.csv'), interval,
                                                      step=True, potentialEnergy=True, temperature=True, density=True))
simulation.reporters.append(mrattle.StateDataReporter(os.sys.stdout, interval, step=True, temperature=True,
                                                      density=True, speed=True))
simulation.step(arguments.steps)
