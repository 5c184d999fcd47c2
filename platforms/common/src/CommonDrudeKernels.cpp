#include "CommonMRattleKernelSources.h"
#include "CommonStepKernels.h"
#include "MRattleDrudeLangevinIntegrator.h"
#include "internal/DrudeGroups.h"
#include "openmm/common/ContextSelector.h"

using namespace MRattlePlugin;
using namespace OpenMM;

// ---- MRattleDrudeLangevinIntegrator

void CommonIntegrateMRattleDrudeLangevinStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                               const RigidBodyIntegrator& integrator) {
    const DrudeGroups groups(system, topology, IntegratorNames::MRattleDrudeLangevin.integrator);
    ContextSelector selector(state.computeContext());
    state.initialize(system, topology, CommonMRattleKernelSources::drude);
    state.setDrudeGroups(groups);
    state.initRandomNumbers(static_cast<const MRattleDrudeLangevinIntegrator&>(integrator).getRandomNumberSeed());
}

void CommonIntegrateMRattleDrudeLangevinStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& bound,
                                                            bool& forcesAreValid) {
    const MRattleDrudeLangevinIntegrator& integrator = static_cast<const MRattleDrudeLangevinIntegrator&>(bound);
    ContextSelector selector(state.computeContext());
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const double friction = integrator.getFriction(), drudeFriction = integrator.getDrudeFriction();
    // MRattleLangevinIntegrator's step with the split noise (a kernel of its own between two
    // passes), then the hard wall after the drift (another) and the projection (a third pass).
    state.beginStep(context, integrator, forcesAreValid);
    state.kick(h);
    state.project(tolerance);
    if (friction == 0 && drudeFriction == 0)
        state.driftAndReset(0.0, h, tolerance);
    else {
        state.driftAndReset(0.0, 0.5 * h, tolerance);
        state.addDrudeNoise(friction, integrator.getTemperature(), drudeFriction, integrator.getDrudeTemperature(), h);
        state.project(tolerance);
        state.driftAndReset(0.0, 0.5 * h, tolerance);
    }
    state.bounceDrudes(integrator.getMaxDrudeDistance(), integrator.getDrudeTemperature(), h);
    state.project(tolerance);
    state.endStep(h, forcesAreValid);
}
