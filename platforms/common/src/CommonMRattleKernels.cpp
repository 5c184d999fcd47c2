#include "CommonStepKernels.h"
#include "MRattleLangevinIntegrator.h"
#include "openmm/common/ContextSelector.h"

using namespace MRattlePlugin;
using namespace OpenMM;

void CommonIntegrateMRattleStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                               bool& forcesAreValid) {
    ContextSelector selector(state.computeContext());
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    // Velocity Verlet: half kick, drift and reset (one pass), new forces, half kick and projection (one pass).
    state.beginStep(context, integrator, forcesAreValid);
    state.driftAndReset(0.5 * h, h, tolerance);
    state.computeForces(context, integrator, forcesAreValid);
    state.kick(0.5 * h);
    state.project(tolerance);
    state.endStep(h, forcesAreValid);
}

void CommonIntegrateMRattleLangevinStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                          const RigidBodyIntegrator& integrator) {
    state.initialize(system, topology);
    state.initRandomNumbers(static_cast<const MRattleLangevinIntegrator&>(integrator).getRandomNumberSeed());
}

void CommonIntegrateMRattleLangevinStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& bound,
                                                       bool& forcesAreValid) {
    const MRattleLangevinIntegrator& integrator = static_cast<const MRattleLangevinIntegrator&>(bound);
    ContextSelector selector(state.computeContext());
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const double friction = integrator.getFriction();
    // LangevinMiddle: kick and projection, half drift and reset, noise and projection (one
    // pass), half drift and reset, projection (a second). The next step's beginStep computes
    // the forces, after any barostat move or reordering: one evaluation a step.
    state.beginStep(context, integrator, forcesAreValid);
    state.kick(h);
    state.project(tolerance);
    if (friction == 0)
        state.driftAndReset(0.0, h, tolerance);
    else {
        state.driftAndReset(0.0, 0.5 * h, tolerance);
        state.addNoise(friction, integrator.getTemperature(), h);
        state.project(tolerance);
        state.driftAndReset(0.0, 0.5 * h, tolerance);
    }
    state.project(tolerance);
    state.endStep(h, forcesAreValid);
}
