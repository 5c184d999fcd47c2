#include "ReferenceRigidSplittingKernels.h"
#include "mrattle/RigidBodyRotor.h"
#include "openmm/OpenMMException.h"
#include <climits>
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void ReferenceIntegrateRigidSplittingStepKernel::execute(ContextImpl& context, const RigidSplittingIntegrator& integrator,
                                                         bool& forcesAreValid) {
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    // Velocity Verlet: half kick and the rotors' position step, new forces, half kick and projection.
    dynamics.beginStep(context, integrator, forcesAreValid);
    dynamics.ownPhase([&] { rotorPositionStep(h, tolerance); });
    dynamics.computeForces(context, integrator, forcesAreValid);
    dynamics.kick(0.5 * h);
    dynamics.project(tolerance, false);
    dynamics.endStep(h, forcesAreValid);
}

void ReferenceIntegrateRigidSplittingStepKernel::rotorPositionStep(double h, double tolerance) {
    ReferenceRigidBodyOperations& ops = dynamics.operations();
    vector<Vec3>& x = dynamics.positions();
    vector<Vec3>& v = dynamics.velocities();
    const vector<Vec3>& f = dynamics.forces();
    vector<Vec3>& newPositions = dynamics.newPositions();
    vector<Vec3>& newVelocities = dynamics.newVelocities();
    const vector<double>& inverseMass = ops.inverseMasses();
    const RigidBodyTopology& bodies = ops.topology();
    const int n = x.size();

    // Free particles: half kick and drift, then RATTLE for their constraints (body atoms
    // are overwritten below; they take no part in free constraints).
    for (int i = 0; i < n; i++)
        newPositions[i] = (inverseMass[i] != 0 ? x[i] + (v[i] + f[i] * (0.5 * h * inverseMass[i])) * h : x[i]);
    ops.constrainFreePositions(x, newPositions, tolerance);
    const int failed = ops.forEachBody([&](int b) {
        return RigidBodyRotor::positionStep(ops.view(b), coordinates(x), coordinates(v), coordinates(f), h,
                                            coordinates(newPositions), coordinates(newVelocities));
    });
    if (failed != INT_MAX)
        throw OpenMMException("rigid body " + std::to_string(failed) +
                                  " would turn by more than a quarter turn in one step, or its motion is not finite; "
                                  "the step size is too large for the forces, or they are not finite");
    // Free particles: refuse what is not finite, as for bodies (the Context is not yet changed).
    for (int i : bodies.getFreeParticles())
        if (!std::isfinite(newPositions[i][0] + newPositions[i][1] + newPositions[i][2]))
            throw OpenMMException("particle " + std::to_string(i) +
                                  " would move to a position that is not finite; the forces are not finite");
    // Free particles' velocities from their displacement (massless ones keep theirs).
    const double inverseStep = 1.0 / h;
    for (int i = 0; i < n; i++) {
        if (inverseMass[i] == 0)
            newVelocities[i] = v[i];
        else if (bodies.getBodyOfParticle(i) < 0)
            newVelocities[i] = (newPositions[i] - x[i]) * inverseStep;
    }
    dynamics.acceptNewState();
}
