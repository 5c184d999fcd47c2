#!/usr/bin/env python3
"""How much faster a step gets when removeIntraBodyInteractions() drops intra-body terms.

Times MRattleIntegrator steps (processor time, best of several repeats, one CPU thread)
on the 27-benzene cluster (vacuum, no cutoff) and on liquid benzene (PME), with the
builders' full OPLS-like System and with the stripped one. (That both give the same
trajectory is checked in tests/python/test_interactions.py.)

    python3 examples/intra_body_speedup.py --steps 50 --repeats 10
"""
import argparse
import time

import openmm
from openmm import unit

import mrattle

parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
parser.add_argument('--steps', type=int, default=50, help='steps per timing (default 50)')
parser.add_argument('--repeats', type=int, default=10, help='timings per case; the best is kept (default 10)')
parser.add_argument('--liquid-molecules', type=int, default=64, help='liquid benzene size (default 64)')
parser.add_argument('--liquid-cutoff', type=float, default=0.9, help='nm, at most half the box edge (default 0.9)')
arguments = parser.parse_args()


def makeContext(system, model, platformName):
    integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    properties = {'Threads': '1'} if platformName == 'CPU' else {}
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName(platformName), properties)
    context.setPositions(model.positions)
    if model.velocities is not None:
        context.setVelocities(model.velocities)
    else:
        context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    integrator.step(10)
    return context


def timeSteps(contexts):
    """Best processor time per step (ms) of each context. Processor time, not wall time, and
    the contexts take turns, so other work on a shared machine disturbs the comparison less."""
    best = [float('inf')]*len(contexts)
    for repeat in range(arguments.repeats):
        for index, context in enumerate(contexts):
            start = time.process_time()
            context.getIntegrator().step(arguments.steps)
            best[index] = min(best[index], (time.process_time() - start)/arguments.steps*1000)
    return best


cases = [('27-benzene cluster (324 atoms, no cutoff)', mrattle.models.benzeneCluster()),
         ('liquid benzene (%d molecules, PME)' % arguments.liquid_molecules,
          mrattle.models.benzeneLiquid(numMolecules=arguments.liquid_molecules,
                                       cutoff=arguments.liquid_cutoff*unit.nanometers))]
print('%-42s %-9s %12s %12s %8s' % ('system', 'platform', 'full ms/step', 'stripped', 'speedup'))
for name, model in cases:
    stripped = mrattle.removeIntraBodyInteractions(model.system, model.positions, 'molecules')
    for platformName in ('Reference', 'CPU'):
        contexts = [makeContext(system, model, platformName) for system in (model.system, stripped)]
        full, reduced = timeSteps(contexts)
        print('%-42s %-9s %12.2f %12.2f %7.2fx' % (name, platformName, full, reduced, full/reduced))
