#include "ReferenceRigidSplittingKernels.h"
#include "mrattle/RigidBodyRotor.h"
#include "openmm/internal/ContextImpl.h"

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void ReferenceIntegrateRigidSplittingStepKernel::integratePositions(ContextImpl& context,
                                                                   const RigidBodyIntegrator& integrator) {
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
    for (int b = 0; b < bodies.getNumBodies(); b++)
        RigidBodyRotor::positionStep(dynamics->view(b), coordinates(x), coordinates(v), coordinates(f), h,
                                     coordinates(newPositions), coordinates(newVelocities));
    const double inverseStep = 1.0 / h;
    for (int i = 0; i < n; i++) {
        if (inverseMass[i] != 0) {
            v[i] = (bodies.getBodyOfParticle(i) < 0 ? (newPositions[i] - x[i]) * inverseStep : newVelocities[i]);
            x[i] = newPositions[i];
        }
    }
    context.computeVirtualSites();  // OpenMM 7.7 and 8.x alike
}
