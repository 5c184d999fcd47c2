#include "CommonMRattleKernelSources.h"
#include "CommonStepKernels.h"
#include "MRattleBussiIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "internal/RigidBodyThermostats.h"
#include "openmm/common/ContextSelector.h"
#include "openmm/common/IntegrationUtilities.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void CommonThermostatStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                         bool& forcesAreValid) {
    ContextSelector selector(state.computeContext());
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    // The thermostat's half step, velocity Verlet (as MRattleIntegrator's), its half step again;
    // uncoupled, MRattleIntegrator's step.
    const bool coupled = collisionFrequency(integrator) != 0;
    state.beginStep(context, integrator, forcesAreValid);
    if (coupled) {
        halfStep(integrator);
        state.scaleVelocities();
    }
    state.driftAndReset(0.5 * h, h, tolerance);
    state.computeForces(context, integrator, forcesAreValid);
    state.kick(0.5 * h);
    state.project(tolerance);
    if (coupled) {
        halfStep(integrator);
        state.scaleVelocities();
    }
    state.endStep(h, forcesAreValid);
}

// ---- Nose-Hoover chain

void CommonIntegrateMRattleNoseHooverStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                            const RigidBodyIntegrator& base) {
    const MRattleNoseHooverIntegrator& integrator = static_cast<const MRattleNoseHooverIntegrator&>(base);
    ContextSelector selector(state.computeContext());
    state.initialize(system, topology, CommonMRattleKernelSources::thermostats);
    const int length = integrator.getChainLength();
    const vector<int> chain = state.declareIntegratorArrays({{"chainPositions", length}, {"chainVelocities", length}}, true);
    const vector<double> w = RigidBodyThermostats::yoshidaSuzukiWeights(integrator.getNumYoshidaSuzukiTimeSteps());
    state.initializeMixedArray(weights, w, "mrattleYoshidaSuzukiWeights");
    kernel = state.program()->createKernel("noseHooverChainHalfStep");
    CommonRigidBodyState::Arguments arguments = state.integratorArguments(kernel);
    arguments.add(length);
    arguments.add(chain[0]);
    arguments.add(chain[1]);
    arguments.add(weights);
    arguments.add((int) w.size());
    arguments.add(integrator.getNumMultiTimeSteps());
    argumentDof = arguments.addMixed(0.0);
    argumentKT = arguments.addMixed(0.0);
    argumentFrequency = arguments.addMixed(0.0);
    argumentHalfStep = arguments.addMixed(0.0);
}

double CommonIntegrateMRattleNoseHooverStepKernel::collisionFrequency(const RigidBodyIntegrator& integrator) const {
    return static_cast<const MRattleNoseHooverIntegrator&>(integrator).getCollisionFrequency();
}

void CommonIntegrateMRattleNoseHooverStepKernel::halfStep(const RigidBodyIntegrator& base) {
    const MRattleNoseHooverIntegrator& integrator = static_cast<const MRattleNoseHooverIntegrator&>(base);
    state.sumKineticEnergy();
    state.setMixedArg(kernel, argumentDof, state.degreesOfFreedom());
    state.setMixedArg(kernel, argumentKT, BOLTZ * integrator.getTemperature());
    state.setMixedArg(kernel, argumentFrequency, integrator.getCollisionFrequency());
    state.setMixedArg(kernel, argumentHalfStep, 0.5 * integrator.getStepSize());
    state.launch(kernel, CommonRigidBodyState::ReductionThreads, CommonRigidBodyState::ReductionThreads);
}

double CommonIntegrateMRattleNoseHooverStepKernel::computeHeatBathEnergy(ContextImpl& context,
                                                                        const RigidBodyIntegrator& base) {
    const MRattleNoseHooverIntegrator& integrator = static_cast<const MRattleNoseHooverIntegrator&>(base);
    const RigidBodyThermostats::NoseHooverChain chain =
        RigidBodyThermostats::NoseHooverChain::fromParameters(state.getIntegratorParameters(context));
    return chain.energy(state.degreesOfFreedom(), BOLTZ * integrator.getTemperature(), integrator.getCollisionFrequency());
}

// ---- CSVR

void CommonIntegrateMRattleBussiStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                       const RigidBodyIntegrator& base) {
    const MRattleBussiIntegrator& integrator = static_cast<const MRattleBussiIntegrator&>(base);
    ContextSelector selector(state.computeContext());
    state.initialize(system, topology, CommonMRattleKernelSources::thermostats);
    state.initRandomNumbers(integrator.getRandomNumberSeed());
    const int work = state.declareIntegratorArrays({{"rescalingWork", 1}}, false)[0];
    kernel = state.program()->createKernel("stochasticRescalingHalfStep");
    CommonRigidBodyState::Arguments arguments = state.integratorArguments(kernel);
    arguments.add(state.computeContext().getIntegrationUtilities().getRandom());
    argumentRandomIndex = arguments.add(0u);
    arguments.add(4 * CsvrRandomValues);
    argumentDof = arguments.add(0);
    argumentKT = arguments.addMixed(0.0);
    argumentC = arguments.addMixed(0.0);
    arguments.add(work);
}

double CommonIntegrateMRattleBussiStepKernel::collisionFrequency(const RigidBodyIntegrator& integrator) const {
    return static_cast<const MRattleBussiIntegrator&>(integrator).getCollisionFrequency();
}

void CommonIntegrateMRattleBussiStepKernel::halfStep(const RigidBodyIntegrator& base) {
    const MRattleBussiIntegrator& integrator = static_cast<const MRattleBussiIntegrator&>(base);
    state.sumKineticEnergy();
    // After the sums' flush: the queued phases' random numbers come first.
    kernel->setArg(argumentRandomIndex,
                   (unsigned int) state.computeContext().getIntegrationUtilities().prepareRandomNumbers(CsvrRandomValues));
    kernel->setArg(argumentDof, state.degreesOfFreedom());
    state.setMixedArg(kernel, argumentKT, BOLTZ * integrator.getTemperature());
    state.setMixedArg(kernel, argumentC, std::exp(-integrator.getCollisionFrequency() * 0.5 * integrator.getStepSize()));
    state.launch(kernel, CommonRigidBodyState::ReductionThreads, CommonRigidBodyState::ReductionThreads);
}

double CommonIntegrateMRattleBussiStepKernel::computeHeatBathEnergy(ContextImpl& context, const RigidBodyIntegrator& base) {
    return -RigidBodyThermostats::csvrWork(state.getIntegratorParameters(context));
}
