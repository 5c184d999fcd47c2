#include "CommonMRattleKernels.h"

using namespace MRattlePlugin;
using namespace OpenMM;

void CommonIntegrateMRattleStepKernel::execute(ContextImpl& context, const MRattleIntegrator& integrator,
                                               bool& forcesAreValid) {
    ContextSelector selector(dynamics.computeContext());
    const double h = integrator.getStepSize();
    // Velocity Verlet: half kick, drift and reset (one pass), new forces, half kick and
    // projection (one pass).
    dynamics.beginStep(context, integrator, forcesAreValid);
    CommonRigidBodyDynamics::Pass first;
    first.kickTime = 0.5 * h;
    first.driftTime = h;
    dynamics.advance(first);
    dynamics.computeForces(context, integrator, forcesAreValid);
    CommonRigidBodyDynamics::Pass second;
    second.kickTime = 0.5 * h;
    second.projectAfterKick = true;
    dynamics.advance(second);
    dynamics.endStep(h, forcesAreValid);
}
