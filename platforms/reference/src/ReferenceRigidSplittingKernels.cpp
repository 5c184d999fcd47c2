#include "ReferenceRigidSplittingKernels.h"
#include "mrattle/RigidBodyRotor.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include <climits>
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void ReferenceIntegrateRigidSplittingStepKernel::integratePositions(ContextImpl& context,
                                                                   const RigidSplittingIntegrator& integrator) {
    vector<Vec3>& x = ReferenceRigidBodyDynamics::positions(context);
    vector<Vec3>& v = ReferenceRigidBodyDynamics::velocities(context);
    vector<Vec3>& f = ReferenceRigidBodyDynamics::forces(context);
    const vector<double>& inverseMass = dynamics->inverseMasses();
    const RigidBodyTopology& bodies = dynamics->topology();
    const double h = integrator.getStepSize();
    const int n = x.size();

    // Free particles: half kick and drift, then RATTLE for their constraints (body atoms
    // are overwritten below; they take no part in free constraints).
    for (int i = 0; i < n; i++)
        newPositions[i] = (inverseMass[i] != 0 ? x[i] + (v[i] + f[i] * (0.5 * h * inverseMass[i])) * h : x[i]);
    dynamics->constrainFreePositions(x, newPositions, integrator.getConstraintTolerance());
    const int failed = dynamics->forEachBody([&](int b) {
        return RigidBodyRotor::positionStep(dynamics->view(b), coordinates(x), coordinates(v), coordinates(f), h,
                                            coordinates(newPositions), coordinates(newVelocities));
    });
    if (failed != INT_MAX)
        throw OpenMMException("RigidSplittingIntegrator: rigid body " + std::to_string(failed) +
                                  " would turn by more than a quarter turn in one step, or its motion is not finite; "
                                  "the step size is too large for the forces, or they are not finite");
    // Free particles: refuse what is not finite, as for bodies (the Context is not yet changed).
    for (int i : bodies.getFreeParticles())
        if (!std::isfinite(newPositions[i][0] + newPositions[i][1] + newPositions[i][2]))
            throw OpenMMException("RigidSplittingIntegrator: particle " + std::to_string(i) +
                                  " would move to a position that is not finite; the forces are not finite");
    const double inverseStep = 1.0 / h;
    for (int i = 0; i < n; i++) {
        if (inverseMass[i] != 0) {
            v[i] = (bodies.getBodyOfParticle(i) < 0 ? (newPositions[i] - x[i]) * inverseStep : newVelocities[i]);
            x[i] = newPositions[i];
        }
    }
    placeVirtualSites(context);
}
