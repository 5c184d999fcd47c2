#include "ReferenceMRattleKernels.h"

using namespace MRattlePlugin;
using namespace OpenMM;

void ReferenceIntegrateMRattleStepKernel::execute(ContextImpl& context, const MRattleIntegrator& integrator,
                                                  bool& forcesAreValid) {
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    // Velocity Verlet: half kick, drift and reset, new forces, half kick and projection.
    dynamics.beginStep(context, integrator, forcesAreValid);
    dynamics.driftAndReset(0.5 * h, h, tolerance);
    dynamics.computeForces(context, integrator, forcesAreValid);
    dynamics.kick(0.5 * h);
    dynamics.project(tolerance, false);
    dynamics.endStep(h, forcesAreValid);
}
