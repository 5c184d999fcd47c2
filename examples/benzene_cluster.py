#!/usr/bin/env python3
"""NVE dynamics of a cluster of 27 rigid benzene molecules with M-RATTLE.

Writes to the output folder: cluster.pdb (topology and first frame), trajectory.dcd,
energies.csv (the rigid-body StateDataReporter's log), energies.png (energies against
time), and prints a summary: total-energy drift and fluctuation, the largest change of
any intra-molecular distance, the temperature with the rigid-body degrees of freedom,
and the speed.

    python3 examples/benzene_cluster.py --steps 5000 --step-size 2 --temperature 250
"""
import argparse
import os
import sys
import time

import numpy as np
import openmm
from openmm import app, unit

import mrattle


def parseArguments():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--steps', type=int, default=5000, help='number of steps (default 5000)')
    parser.add_argument('--step-size', type=float, default=2.0, help='step size in fs (default 2)')
    parser.add_argument('--temperature', type=float, default=250.0, help='initial temperature in K (default 250)')
    parser.add_argument('--platform', default='CPU', choices=mrattle.PLATFORMS, help='OpenMM platform (default CPU)')
    parser.add_argument('--threads', type=int, default=0, help='CPU threads (default: all cores)')
    parser.add_argument('--report-interval', type=int, default=50, help='steps between reports (default 50)')
    parser.add_argument('--seed', type=int, default=1, help='random seed of orientations and velocities')
    parser.add_argument('--output', default='output', help='output folder (default ./output)')
    parser.add_argument('--integrator', default='mrattle', choices=['mrattle', 'splitting'],
                        help='M-RATTLE (default) or the symplectic-splitting baseline, for comparison')
    parser.add_argument('--keep-intra-body', action='store_true',
                        help='keep the interactions inside molecules (they cannot affect the motion)')
    arguments = parser.parse_args()
    if arguments.steps < 1 or arguments.step_size <= 0 or arguments.report_interval < 1:
        parser.error('steps, step size and report interval must be positive')
    return arguments


class RigidityMonitor(object):
    """A reporter recording the largest change of any distance inside a rigid body."""

    def __init__(self, bodies, positions, interval):
        self.pairs = np.array([(i, j) for body in bodies for a, i in enumerate(body) for j in body[a + 1:]])
        self.reference = self._distances(positions)
        self.interval = interval
        self.largestError = 0.0

    def _distances(self, positions):
        return np.linalg.norm(positions[self.pairs[:, 0]] - positions[self.pairs[:, 1]], axis=1)

    def describeNextReport(self, simulation):
        return (self.interval - simulation.currentStep % self.interval, True, False, False, False)

    def report(self, simulation, state):
        positions = state.getPositions(asNumpy=True).value_in_unit(unit.nanometers)
        self.largestError = max(self.largestError, np.abs(self._distances(positions) - self.reference).max())


def plotEnergies(csvPath, pngPath, method):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    data = np.genfromtxt(csvPath, delimiter=',', names=True)
    time_ps = data['Time_ps']
    figure, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
    top.plot(time_ps, data['Potential_Energy_kJmole'], label='potential')
    top.plot(time_ps, data['Kinetic_Energy_kJmole'], label='kinetic')
    top.plot(time_ps, data['Total_Energy_kJmole'], label='total')
    top.set_ylabel('energy (kJ/mol)')
    top.legend(loc='center right')
    top.set_title('27 rigid benzene molecules, NVE, %s' % method)
    total = data['Total_Energy_kJmole']
    bottom.plot(time_ps, total - total[0], color='C2')
    bottom.set_ylabel('total energy - initial (kJ/mol)')
    bottom.set_xlabel('time (ps)')
    figure.tight_layout()
    figure.savefig(pngPath, dpi=100)
    plt.close(figure)
    return data


def main():
    arguments = parseArguments()
    os.makedirs(arguments.output, exist_ok=True)
    model = mrattle.models.benzeneCluster(temperature=arguments.temperature*unit.kelvin, seed=arguments.seed)
    system = model.system
    if not arguments.keep_intra_body:
        system = mrattle.removeIntraBodyInteractions(system, model.positions, 'molecules')

    integratorClass = mrattle.MRattleIntegrator if arguments.integrator == 'mrattle' else mrattle.RigidSplittingIntegrator
    integrator = integratorClass(arguments.step_size*unit.femtoseconds)
    platform = openmm.Platform.getPlatformByName(arguments.platform)
    properties = {'Threads': str(arguments.threads)} if arguments.platform == 'CPU' and arguments.threads > 0 else {}
    simulation = app.Simulation(model.topology, system, integrator, platform, properties)
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocities(model.velocities)

    csvPath = os.path.join(arguments.output, 'energies.csv')
    pdbPath = os.path.join(arguments.output, 'cluster.pdb')
    with open(pdbPath, 'w') as pdb:
        app.PDBFile.writeFile(model.topology, model.positions, pdb)
    interval = min(arguments.report_interval, arguments.steps)
    simulation.reporters.append(mrattle.StateDataReporter(
        csvPath, interval, step=True, time=True, potentialEnergy=True, kineticEnergy=True, totalEnergy=True,
        temperature=True, speed=True))
    simulation.reporters.append(app.DCDReporter(os.path.join(arguments.output, 'trajectory.dcd'), interval))
    rigidity = RigidityMonitor(integrator.getBodiesInEffect(), np.array(model.positions.value_in_unit(unit.nanometers)),
                               interval)
    simulation.reporters.append(rigidity)
    # Progress and time left on stderr: OpenMM's own reporter.
    simulation.reporters.append(app.StateDataReporter(sys.stderr, max(1, arguments.steps//10), progress=True,
                                                      remainingTime=True, speed=True, totalSteps=arguments.steps))

    start = time.time()
    simulation.step(arguments.steps)
    wallTime = time.time() - start

    method = 'M-RATTLE' if arguments.integrator == 'mrattle' else 'rigid-body splitting'
    data = plotEnergies(csvPath, os.path.join(arguments.output, 'energies.png'), method)
    total = np.atleast_1d(data['Total_Energy_kJmole'])
    kinetic = np.atleast_1d(data['Kinetic_Energy_kJmole'])
    times = np.atleast_1d(data['Time_ps'])
    temperature = np.atleast_1d(data['Temperature_K'])
    drift = np.polyfit(times, total, 1)[0]*1000 if len(times) > 1 else float('nan')
    simulatedNs = arguments.steps*arguments.step_size*1e-6
    rows = [
        ('molecules / atoms', '%d / %d' % (integrator.getNumBodiesInEffect(), system.getNumParticles())),
        ('degrees of freedom', '%d (6 per rigid molecule)' % integrator.getNumDegreesOfFreedom()),
        ('steps x step size', '%d x %g fs = %g ps' % (arguments.steps, arguments.step_size, arguments.steps*arguments.step_size/1000)),
        ('total energy drift', '%.3g kJ/mol/ns (linear fit)' % drift),
        ('total energy fluctuation', '%.3g kJ/mol (std), %.2g of kinetic std' %
         (total.std(), total.std()/kinetic.std() if kinetic.std() > 0 else float('nan'))),
        ('largest rigidity error', '%.3g nm (largest change of an intra-molecular distance)' % rigidity.largestError),
        ('temperature', '%.1f +- %.1f K (mean +- std, rigid-body DOF)' % (temperature.mean(), temperature.std())),
        ('speed', '%.1f ns/day (%.1f s wall, %s platform)' % (simulatedNs/(wallTime/86400), wallTime, arguments.platform)),
        ('files', ', '.join(sorted(os.listdir(arguments.output)))),
    ]
    width = max(len(name) for name, value in rows)
    print('\n%s NVE run of a 27-benzene cluster' % ('M-RATTLE' if arguments.integrator == 'mrattle'
                                                   else 'Symplectic-splitting'))
    print('-'*(width + 50))
    for name, value in rows:
        print('%-*s  %s' % (width, name, value))
    print('-'*(width + 50))
    print('output in %s' % os.path.abspath(arguments.output))


if __name__ == '__main__':
    main()
