#include "CommonStepKernels.h"
#include "MRattleLangevinIntegrator.h"
#include "openmm/common/ContextSelector.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;

void CommonIntegrateMRattleStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                  const RigidBodyIntegrator& integrator) {
    state.initialize(system, topology);
}

void CommonIntegrateMRattleStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                               bool& forcesAreValid) {
    ContextSelector selector(state.computeContext());
    const double h = integrator.getStepSize();
    state.beginStep(context, integrator, forcesAreValid);
    state.kick(0.5 * h);
    state.driftAndReset(h);
    state.computeForces(context, integrator, forcesAreValid);
    state.kick(0.5 * h);
    state.project();
    state.endStep(h, forcesAreValid);
}

void CommonIntegrateMRattleLangevinStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                          const RigidBodyIntegrator& integrator) {
    state.initialize(system, topology);
    state.initRandomNumbers(static_cast<const MRattleLangevinIntegrator&>(integrator).getRandomNumberSeed());
}

void CommonIntegrateMRattleLangevinStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& base,
                                                       bool& forcesAreValid) {
    const MRattleLangevinIntegrator& integrator = static_cast<const MRattleLangevinIntegrator&>(base);
    ContextSelector selector(state.computeContext());
    const double h = integrator.getStepSize(), friction = integrator.getFriction();
    state.beginStep(context, integrator, forcesAreValid);
    state.kick(h);
    state.project();
    if (friction == 0)
        state.driftAndReset(h);
    else {
        const double a = std::exp(-friction * h);
        state.driftAndReset(0.5 * h);
        state.addNoise(a, std::sqrt((1 - a * a) * BOLTZ * integrator.getTemperature()));
        state.project();
        state.driftAndReset(0.5 * h);
    }
    state.project();
    state.computeForces(context, integrator, forcesAreValid);
    state.endStep(h, forcesAreValid);
}
