#include "ReferenceMRattleKernels.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include "openmm/internal/ContextImpl.h"

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void ReferenceIntegrateMRattleStepKernel::integratePositions(ContextImpl& context, const RigidBodyIntegrator& integrator) {
    vector<Vec3>& x = ReferenceRigidBodyDynamics::positions(context);
    vector<Vec3>& v = ReferenceRigidBodyDynamics::velocities(context);
    const vector<Vec3>& f = ReferenceRigidBodyDynamics::forces(context);
    const vector<double>& inverseMass = dynamics->inverseMasses();
    const double h = integrator.getStepSize();
    const int n = x.size();

    // Half kick and drift into buffers: the Context is only written once every body's
    // reset has succeeded, so a failed step leaves it as it was.
    for (int i = 0; i < n; i++) {
        if (inverseMass[i] != 0) {
            newVelocities[i] = v[i] + f[i] * (0.5 * h * inverseMass[i]);
            newPositions[i] = x[i] + newVelocities[i] * h;
        } else {
            newVelocities[i] = v[i];
            newPositions[i] = x[i];
        }
    }
    // Free particles: RATTLE for their constraints, velocities from the displacement.
    dynamics->constrainFreePositions(x, newPositions, integrator.getConstraintTolerance());
    const double inverseStep = 1.0 / h;
    for (int i : dynamics->topology().getFreeParticles()) {
        newVelocities[i] = (newPositions[i] - x[i]) * inverseStep;
        if (!std::isfinite(newPositions[i][0] + newPositions[i][1] + newPositions[i][2] + newVelocities[i][0] +
                           newVelocities[i][1] + newVelocities[i][2]))
            throw OpenMMException("MRattleIntegrator: particle " + std::to_string(i) +
                                  " would move to a position that is not finite; its force or velocity is not finite");
    }
    // Bodies: M-RATTLE's reset, new positions and velocities formed from displacements.
    for (int b = 0; b < dynamics->topology().getNumBodies(); b++) {
        RigidBodyMath::RotationSolve solve = RigidBodyMath::driftAndResetBody(
            dynamics->view(b), h, coordinates(x), coordinates(newVelocities), coordinates(newPositions));
        if (!solve.converged)
            throw OpenMMException("MRattleIntegrator: the position reset of rigid body " + std::to_string(b) +
                                  " found no rotation in " + std::to_string(RigidBodyMath::MaxRotationIterations) +
                                  " Newton iterations; the step size is too large for the forces, or they are not finite");
    }
    x.swap(newPositions);
    v.swap(newVelocities);
    context.computeVirtualSites();  // OpenMM 7.7 and 8.x alike
}
