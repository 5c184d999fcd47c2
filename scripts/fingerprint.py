#!/usr/bin/env python3
"""Fingerprint the integrators' behaviour: one SHA-256 line per platform, integrator, model
and item, so two builds can be compared bit for bit (a refactor must not change a line).

    scripts/python.sh scripts/fingerprint.py after.txt      # this build
    PYTHONPATH=<other build>/python /usr/bin/python3 scripts/fingerprint.py before.txt
    diff before.txt after.txt

Items, for each integrator on Reference, CPU (one thread) and OpenCL (double precision, where
the integrator runs): 'start' (setVelocitiesToTemperature), 'run' (after 10 steps),
'energy' (potential and kinetic energy and the kinetic split), 'restart' (10 steps after
loading a checkpoint, which must equal the 10 steps run straight on: checked, 'MISMATCH'
otherwise), 'checkpoint' (the checkpoint's bytes: a change of the checkpoint format changes
this line alone), 'xml' (the integrator's and the state's XML). Arrays are hashed as float64
bytes. Models: 27 rigid waters in a PME box, three of them left free with their constraints
(free-particle RATTLE); 27 benzenes in vacuum with an AndersenThermostat (body collisions);
for the Drude integrators alone, 8 SWM4-NDP waters in vacuum (rigid O-H-H, free Drude particles).
"""
import hashlib
import sys

import numpy as np
import openmm
from openmm import unit

import mrattle

STEPS = 10
INTEGRATORS = {
    'MRattle': lambda: mrattle.MRattleIntegrator(0.002),
    'MRattleLangevin': lambda: _seeded(mrattle.MRattleLangevinIntegrator(300, 1.0, 0.002)),
    'RigidSplitting': lambda: mrattle.RigidSplittingIntegrator(0.002),
    'MRattleNoseHoover': lambda: mrattle.MRattleNoseHooverIntegrator(300, 10.0, 0.002),
    'MRattleBussi': lambda: _seeded(mrattle.MRattleBussiIntegrator(300, 10.0, 0.002)),
}
# The Drude integrators (where the build has OpenMM's Drude plugin) run the SWM4-NDP model alone.
if hasattr(mrattle, 'MRattleDrudeLangevinIntegrator'):
    INTEGRATORS['MRattleDrudeLangevin'] = lambda: _seeded(mrattle.MRattleDrudeLangevinIntegrator(300, 5.0, 1, 20.0, 0.001))
    INTEGRATORS['MRattleDrudeNoseHoover'] = lambda: mrattle.MRattleDrudeNoseHooverIntegrator(300, 10.0, 1, 20.0, 0.001)
# One CPU thread: OpenMM's CPU forces summed on several threads differ from run to run.
# The baseline runs on the host platforms only.
HOST_ONLY = ('RigidSplitting',)
PROPERTIES = {'CPU': {'Threads': '1'}, 'OpenCL': {'Precision': 'double'}}


def _seeded(integrator):
    integrator.setRandomNumberSeed(2024)
    return integrator


def waterWithFreeMolecules():
    model = mrattle.models.waterBox(numMolecules=27, cutoff=0.45*unit.nanometers)
    bodies = [[3*m, 3*m + 1, 3*m + 2] for m in range(24)]  # waters 24-26 free, constrained
    return model.system, model.positions, bodies


def benzeneWithAndersen():
    model = mrattle.models.benzeneCluster()
    model.system.addForce(openmm.AndersenThermostat(300, 5.0))
    model.system.getForce(model.system.getNumForces() - 1).setRandomNumberSeed(11)
    return model.system, model.positions, []


def swm4ndpWithFreeDrudeParticles():
    model = mrattle.models.swm4ndpWater(8)
    return model.system, model.positions, mrattle.rigidBodies(model.topology, model.system)


MODELS = {'water': waterWithFreeMolecules, 'benzene': benzeneWithAndersen, 'swm4ndp': swm4ndpWithFreeDrudeParticles}


def modelsOf(integratorName):
    drude = integratorName.startswith('MRattleDrude')
    return [name for name in MODELS if (name == 'swm4ndp') == drude]


def digest(*parts):
    h = hashlib.sha256()
    for part in parts:
        h.update(part if isinstance(part, bytes) else np.ascontiguousarray(part, dtype=np.float64).tobytes())
    return h.hexdigest()[:16]


def stateDigest(context):
    state = context.getState(getPositions=True, getVelocities=True)
    return digest(state.getPositions(asNumpy=True).value_in_unit(unit.nanometers),
                  state.getVelocities(asNumpy=True).value_in_unit(unit.nanometers/unit.picoseconds),
                  [state.getTime().value_in_unit(unit.picoseconds), state.getStepCount()])


def fingerprint(platformName, integratorName, modelName):
    system, positions, bodies = MODELS[modelName]()
    integrator = INTEGRATORS[integratorName]()
    for body in bodies:
        integrator.addRigidBody(body)
    platform = openmm.Platform.getPlatformByName(platformName)
    context = openmm.Context(system, integrator, platform, PROPERTIES.get(platformName, {}))
    context.setPositions(positions)
    context.setVelocitiesToTemperature(300, 7)
    lines = {'start': stateDigest(context)}
    integrator.step(STEPS)
    lines['run'] = stateDigest(context)
    state = context.getState(getEnergy=True)
    kJ = unit.kilojoules_per_mole
    lines['energy'] = digest([state.getPotentialEnergy().value_in_unit(kJ), state.getKineticEnergy().value_in_unit(kJ),
                              integrator.computeTranslationalKineticEnergy().value_in_unit(kJ),
                              integrator.computeRotationalKineticEnergy().value_in_unit(kJ),
                              integrator.computeFreeKineticEnergy().value_in_unit(kJ)])
    checkpoint = context.createCheckpoint()
    lines['checkpoint'] = digest(checkpoint)
    integrator.step(STEPS)
    straight = stateDigest(context)
    context.loadCheckpoint(checkpoint)
    integrator.step(STEPS)
    restarted = stateDigest(context)
    lines['restart'] = restarted if restarted == straight else 'MISMATCH'
    state = context.getState(getPositions=True, getVelocities=True, getEnergy=True, getParameters=True)
    lines['xml'] = digest(openmm.XmlSerializer.serialize(integrator).encode(),
                          openmm.XmlSerializer.serialize(state).encode())
    return lines


def main(path):
    out = open(path, 'w')  # a file, not stdout: OpenCL compilers print there
    platforms = [p for p in ('Reference', 'CPU', 'OpenCL') if p in mrattle.PLATFORMS]
    for platformName in platforms:
        for integratorName in INTEGRATORS:
            if platformName in mrattle.DEVICE_PLATFORMS and integratorName in HOST_ONLY:
                continue
            for modelName in modelsOf(integratorName):
                for item, value in fingerprint(platformName, integratorName, modelName).items():
                    print(platformName, integratorName, modelName, item, value, file=out)
                out.flush()


if __name__ == '__main__':
    if len(sys.argv) != 2:
        sys.exit('usage: fingerprint.py OUTPUT_FILE')
    main(sys.argv[1])
