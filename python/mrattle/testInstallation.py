"""Check an installation, as OpenMM's ``python -m openmm.testInstallation`` does:

    python3 -m mrattle.testInstallation

lists the platforms that have the plugin's kernels, then runs the 27-benzene cluster for
20 steps of MRattleIntegrator and of MRattleNoseHooverIntegrator on each and compares the
positions with Reference's, and 20 steps of MRattleBussiIntegrator (its random numbers are
each platform's own: it must run and stay finite); where OpenMM has its Drude plugin, 8
polarizable SWM4-NDP waters with MRattleDrudeNoseHooverIntegrator, compared likewise. Exits
non-zero if a platform fails or disagrees.
"""
import sys

import numpy as np
import openmm
from openmm import unit

import mrattle

#: Largest position difference from Reference after the run, per platform (nm): device
#: platforms in their default single precision round far more than in double.
AGREEMENT = {'double': 1e-8, 'mixed': 1e-6, 'single': 1e-4}
STEPS = 20


#: The integrators run: name, how to make it, whether its run is deterministic (compared with
#: Reference's), the model it runs (a mrattle.models builder; bodies from rigidBodies() where not water).
INTEGRATORS = [
    ('MRattleIntegrator', lambda: mrattle.MRattleIntegrator(2*unit.femtoseconds), True,
     mrattle.models.benzeneCluster),
    ('MRattleNoseHooverIntegrator',
     lambda: mrattle.MRattleNoseHooverIntegrator(300*unit.kelvin, 10/unit.picosecond, 2*unit.femtoseconds), True,
     mrattle.models.benzeneCluster),
    ('MRattleBussiIntegrator',
     lambda: mrattle.MRattleBussiIntegrator(300*unit.kelvin, 10/unit.picosecond, 2*unit.femtoseconds), False,
     mrattle.models.benzeneCluster),
]
if hasattr(mrattle, 'MRattleDrudeNoseHooverIntegrator'):
    INTEGRATORS.append(('MRattleDrudeNoseHooverIntegrator',
                        lambda: mrattle.MRattleDrudeNoseHooverIntegrator(300*unit.kelvin, 10/unit.picosecond, 1*unit.kelvin,
                                                                         20/unit.picosecond, 1*unit.femtoseconds),
                        True, mrattle.models.swm4ndpWater))


def runOn(platformName, model, makeIntegrator):
    integrator = makeIntegrator()
    if hasattr(integrator, 'computeDrudeTemperature'):   # its Drude particles stay out of the bodies
        mrattle.declareRigidBodies(integrator, model.topology, model.system)
    context = openmm.Context(model.system, integrator, openmm.Platform.getPlatformByName(platformName))
    context.setPositions(model.positions)
    context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    integrator.step(STEPS)
    return context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)


def main():
    print('OpenMM %s, M-RATTLE plugin %s from %s' % (openmm.Platform.getOpenMMVersion(), mrattle.__version__,
                                                      mrattle.__file__))
    print('Platforms with the plugin\'s kernels: %s' % ', '.join(mrattle.PLATFORMS))
    failures = 0
    for integratorName, makeIntegrator, deterministic, makeModel in INTEGRATORS:
        print('%s:' % integratorName)
        model = makeModel()
        reference = runOn('Reference', model, makeIntegrator)
        for name in mrattle.PLATFORMS:
            try:
                positions = runOn(name, model, makeIntegrator)
            except Exception as error:  # a platform present but unusable here (no device, ...)
                print('  %-10s failed: %s' % (name, error))
                failures += 1
                continue
            if not deterministic:
                finite = bool(np.all(np.isfinite(positions)))
                failures += not finite
                print('  %-10s %s after %d steps' % (name, 'runs' if finite else 'FAILS: positions not finite', STEPS))
                continue
            difference = float(np.abs(positions - reference).max())
            precision = openmm.Platform.getPlatformByName(name).getPropertyDefaultValue('Precision') \
                if name in mrattle.DEVICE_PLATFORMS else 'double'
            limit = AGREEMENT[precision]
            verdict = 'agrees' if difference <= limit else 'DISAGREES'
            failures += (difference > limit)
            print('  %-10s %s with Reference: %.2e nm after %d steps (%s precision, limit %.0e)'
                  % (name, verdict, difference, STEPS, precision, limit))
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
