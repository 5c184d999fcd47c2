#include "ReferenceMRattleKernels.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include "openmm/internal/ContextImpl.h"

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void ReferenceIntegrateMRattleStepKernel::integratePositions(ContextImpl& context, const MRattleIntegrator& integrator) {
    vector<Vec3>& x = ReferenceRigidBodyDynamics::positions(context);
    vector<Vec3>& v = ReferenceRigidBodyDynamics::velocities(context);
    const vector<Vec3>& f = ReferenceRigidBodyDynamics::forces(context);
    const double h = integrator.getStepSize();
    // Half kick, drift and reset into buffers: the Context is only written once every
    // body's reset has succeeded, so a failed step leaves it as it was.
    try {
        dynamics->driftAndReset(x, v, h, integrator.getConstraintTolerance(), newPositions, newVelocities, &f, 0.5 * h);
    } catch (const OpenMMException& e) {
        throw OpenMMException(std::string("MRattleIntegrator: ") + e.what());
    }
    x.swap(newPositions);
    v.swap(newVelocities);
    placeVirtualSites(context);
}
