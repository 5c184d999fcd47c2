"""Energy minimization that keeps the rigid bodies rigid.

``mrattle.minimizeEnergy(context, tolerance, maxIterations)`` is ``openmm.LocalEnergyMinimizer.minimize``
for a Context whose integrator is one of the plugin's (the C++ ``RigidBodyMinimizer``): the
bodies move by translations and rotations, so their shapes never change. After
``import mrattle``, ``app.Simulation.minimizeEnergy()`` does the same for such a Simulation.
"""
import functools
import operator

import openmm.unit as _unit

from .integrators import RigidBodyMinimizer

#: LocalEnergyMinimizer's default tolerance, as app.Simulation.minimizeEnergy gives it.
DEFAULT_TOLERANCE = 10 * _unit.kilojoules_per_mole / _unit.nanometer
_TOLERANCE_UNIT = _unit.kilojoules_per_mole / _unit.nanometer


def _toleranceValue(tolerance):
    if _unit.is_quantity(tolerance):
        if not tolerance.unit.is_compatible(_TOLERANCE_UNIT):
            raise TypeError('minimizeEnergy: the tolerance must be a force (e.g. kJ/mol/nm), got %s' % (tolerance,))
        tolerance = tolerance.value_in_unit(_TOLERANCE_UNIT)
    try:
        return float(tolerance)
    except (TypeError, ValueError):
        raise TypeError('minimizeEnergy: the tolerance must be a number of kJ/mol/nm or a force Quantity, got %r'
                        % (tolerance,)) from None


def minimizeEnergy(context, tolerance=DEFAULT_TOLERANCE, maxIterations=0):
    """Minimize the potential energy over rigid-body coordinates, like LocalEnergyMinimizer.minimize.

    Parameters
    ----------
    context : openmm.Context
        A Context whose integrator is a mrattle integrator (or a CompoundIntegrator holding one);
        on return it holds the minimized positions.
    tolerance : force Quantity or float (kJ/mol/nm)
        As LocalEnergyMinimizer's: the search stops once the root mean square over particles of
        the generalized force (each body's net force and torque, projected on its rigid motion)
        reaches it.
    maxIterations : int
        The most L-BFGS iterations (0: until converged).

    Returns
    -------
    RigidBodyMinimizationReport
        iterations, evaluations, initialEnergy and finalEnergy (kJ/mol), rmsForce (kJ/mol/nm).
    """
    try:
        maxIterations = operator.index(maxIterations)
    except TypeError:
        raise TypeError('minimizeEnergy: maxIterations must be an integer, got %r' % (maxIterations,)) from None
    return RigidBodyMinimizer.minimize(context, _toleranceValue(tolerance), maxIterations)


def installSimulationHook():
    """Make app.Simulation.minimizeEnergy minimize rigidly when the Simulation's integrator is the plugin's.

    OpenMM offers no public hook for the minimizer a Simulation uses, so this replaces the
    public method once (at import) and keeps OpenMM's for every other integrator.
    """
    from openmm import app
    openmmMinimizeEnergy = app.Simulation.minimizeEnergy
    if getattr(openmmMinimizeEnergy, '_mrattleOpenMM', None) is not None:
        return  # installed already

    @functools.wraps(openmmMinimizeEnergy)
    def simulationMinimizeEnergy(self, tolerance=DEFAULT_TOLERANCE, maxIterations=0, *args, **kwargs):
        if not RigidBodyMinimizer.appliesTo(self.context):
            return openmmMinimizeEnergy(self, tolerance, maxIterations, *args, **kwargs)
        # OpenMM 8 adds a MinimizationReporter argument, which reports Cartesian steps.
        extra = [a for a in args if a is not None] + [k for k, v in kwargs.items() if v is not None]
        if extra:
            raise TypeError('Simulation.minimizeEnergy: with a mrattle integrator only tolerance and maxIterations '
                            'are supported (the rigid-body minimizer takes no reporter), got %s' % (extra,))
        minimizeEnergy(self.context, tolerance, maxIterations)

    simulationMinimizeEnergy.__doc__ = (openmmMinimizeEnergy.__doc__ or '') + (
        '\n        With a mrattle integrator (also inside a CompoundIntegrator) this is mrattle.minimizeEnergy:\n'
        '        the rigid bodies translate and rotate, keeping their shapes.\n')
    simulationMinimizeEnergy._mrattleOpenMM = openmmMinimizeEnergy
    app.Simulation.minimizeEnergy = simulationMinimizeEnergy
