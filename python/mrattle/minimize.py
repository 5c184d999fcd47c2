"""Energy minimization that keeps the rigid bodies rigid.

``mrattle.minimizeEnergy(context, tolerance, maxIterations, reporter)`` is
``openmm.LocalEnergyMinimizer.minimize`` for a Context whose integrator is one of the plugin's
(the C++ ``RigidBodyMinimizer``): the bodies move by translations and rotations, so their
shapes never change. After ``import mrattle``, ``openmm.LocalEnergyMinimizer.minimize`` itself
does the same for such a Context, and so ``app.Simulation.minimizeEnergy()``, which calls it.
"""
import operator

import openmm as _openmm
import openmm.unit as _unit

from .integrators import RigidBodyMinimizer, _minimizeReporting

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


def minimizeEnergy(context, tolerance=DEFAULT_TOLERANCE, maxIterations=0, reporter=None):
    """Minimize the potential energy over rigid-body coordinates, like LocalEnergyMinimizer.minimize.

    Parameters
    ----------
    context : openmm.Context
        A Context whose integrator is a mrattle integrator (or a CompoundIntegrator holding one);
        on return it holds the minimized positions.
    tolerance : force Quantity or float (kJ/mol/nm)
        As LocalEnergyMinimizer's: the search stops once the root mean square of the
        generalized force (each body's net force and torque, projected on its rigid motion)
        reaches it (docs/minimization.md, convergence).
    maxIterations : int
        The most L-BFGS iterations (0: until converged).
    reporter : openmm.MinimizationReporter or None
        Any object with OpenMM 8's ``report(iteration, x, grad, args)``, called after each
        iteration with the Cartesian positions, the gradient projected on rigid motion (tuples
        of floats, flattened) and a dict of "system energy", "restraint energy", "restraint
        strength" and "max constraint error"; returning True stops the search. An exception
        it raises is raised again, with the Context at the best point found.

    Returns
    -------
    RigidBodyMinimizationReport
        iterations, evaluations, initialEnergy and finalEnergy (kJ/mol), rmsForce (kJ/mol/nm).
    """
    try:
        maxIterations = operator.index(maxIterations)
    except TypeError:
        raise TypeError('minimizeEnergy: maxIterations must be an integer, got %r' % (maxIterations,)) from None
    tolerance = _toleranceValue(tolerance)
    if reporter is None:
        return RigidBodyMinimizer.minimize(context, tolerance, maxIterations)
    if not callable(getattr(reporter, 'report', None)):
        raise TypeError('minimizeEnergy: the reporter must have a report(iteration, x, grad, args) method '
                        '(an openmm.MinimizationReporter), got %r' % (reporter,))
    return _minimizeReporting(context, tolerance, maxIterations, reporter)


def installLocalEnergyMinimizerHook():
    """Make openmm.LocalEnergyMinimizer.minimize rigid when the Context's integrator is the plugin's.

    OpenMM offers no public hook for its minimizer, so this replaces that public static
    method once (at import) and calls OpenMM's own for every other integrator.
    app.Simulation.minimizeEnergy calls it (OpenMM 7.7 and 8.x), so it needs no hook of its own.
    """
    openmmMinimize = _openmm.LocalEnergyMinimizer.minimize
    if getattr(openmmMinimize, '_mrattleOpenMM', None) is not None:
        return  # installed already

    def minimize(context, tolerance=DEFAULT_TOLERANCE, maxIterations=0, reporter=None):
        if not RigidBodyMinimizer.appliesTo(context):
            if reporter is None:  # OpenMM 7.7's takes no reporter
                return openmmMinimize(context, tolerance, maxIterations)
            return openmmMinimize(context, tolerance, maxIterations, reporter)
        minimizeEnergy(context, tolerance, maxIterations, reporter)

    minimize.__doc__ = (openmmMinimize.__doc__ or '') + (
        '\n        With a mrattle integrator (also inside a CompoundIntegrator) this is mrattle.minimizeEnergy:\n'
        '        the rigid bodies translate and rotate, keeping their shapes.\n')
    minimize._mrattleOpenMM = openmmMinimize
    _openmm.LocalEnergyMinimizer.minimize = staticmethod(minimize)
