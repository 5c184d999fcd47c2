"""Integrators made of OpenMM alone, that the plugin's are checked and benchmarked against.

Both the Python tests (tests/python) and the benchmark suite (benchmarks/suite) compare
M-RATTLE with these, so they live once, here, in the package both already import. The C++
tests have the same integrator in tests/TestSupport.cpp (rattleVerletIntegrator), with the
same steps in the same order.
"""
import openmm


def rattleVerletIntegrator(stepSize, constraintTolerance=1e-10):
    """RATTLE through OpenMM itself: velocity Verlet with the positions constrained after the
    drift (SHAKE, or SETTLE for water) and the velocities after the closing kick.

    A CustomIntegrator; each step: a half kick, the drift, the position constraints, the
    velocity as the constrained displacement over the step, the second half kick, the
    velocity constraints.

    Parameters
    ----------
    stepSize : float (ps) or Quantity (time)
    constraintTolerance : float
        the integrator's constraint tolerance (OpenMM's default is 1e-5)

    Returns
    -------
    openmm.CustomIntegrator
    """
    integrator = openmm.CustomIntegrator(stepSize)
    integrator.setConstraintTolerance(constraintTolerance)
    integrator.addPerDofVariable("x0", 0)
    integrator.addUpdateContextState()
    integrator.addComputePerDof("v", "v+0.5*dt*f/m")
    integrator.addComputePerDof("x0", "x")
    integrator.addComputePerDof("x", "x+dt*v")
    integrator.addConstrainPositions()
    integrator.addComputePerDof("v", "(x-x0)/dt")
    integrator.addComputePerDof("v", "v+0.5*dt*f/m")
    integrator.addConstrainVelocities()
    return integrator
