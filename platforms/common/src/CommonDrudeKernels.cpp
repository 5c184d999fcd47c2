#include "CommonMRattleKernelSources.h"
#include "CommonStepKernels.h"
#include "MRattleDrudeLangevinIntegrator.h"
#include "MRattleDrudeNoseHooverIntegrator.h"
#include "internal/DrudeGroups.h"
#include "internal/RigidBodyThermostats.h"
#include "openmm/common/ContextSelector.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

// ---- MRattleDrudeLangevinIntegrator

void CommonIntegrateMRattleDrudeLangevinStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                               const RigidBodyIntegrator& integrator) {
    const DrudeGroups groups(system, topology, IntegratorNames::MRattleDrudeLangevin.integrator);
    numDrudes = groups.getNumDrudeParticles();
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
    DrudeGroups::requireNumDrudeParticles(context.getSystem(), numDrudes, IntegratorNames::MRattleDrudeLangevin.integrator);
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

double CommonIntegrateMRattleDrudeLangevinStepKernel::computeDrudeKineticEnergy(ContextImpl& context,
                                                                                int& numDrudeParticles) {
    ContextSelector selector(state.computeContext());
    numDrudeParticles = numDrudes;
    return state.computeDrudeKineticEnergy();
}

// ---- MRattleDrudeNoseHooverIntegrator

void CommonIntegrateMRattleDrudeNoseHooverStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                                 const RigidBodyIntegrator& base) {
    const MRattleDrudeNoseHooverIntegrator& integrator = static_cast<const MRattleDrudeNoseHooverIntegrator&>(base);
    const DrudeGroups groups(system, topology, IntegratorNames::MRattleDrudeNoseHoover.integrator);
    numDrudes = groups.getNumDrudeParticles();
    ContextSelector selector(state.computeContext());
    state.initialize(system, topology, CommonMRattleKernelSources::thermostats + CommonMRattleKernelSources::drude);
    state.setDrudeGroups(groups);
    const int length = integrator.getChainLength();
    const vector<int> chains = state.declareIntegratorArrays({{"chainPositions", length},
                                                              {"chainVelocities", length},
                                                              {"drudeChainPositions", length},
                                                              {"drudeChainVelocities", length}},
                                                             true);
    const vector<double> w = RigidBodyThermostats::yoshidaSuzukiWeights(integrator.getNumYoshidaSuzukiTimeSteps());
    state.initializeMixedArray(weights, w, "mrattleYoshidaSuzukiWeights");
    kernel = state.program()->createKernel("drudeNoseHooverChainsHalfStep");
    CommonRigidBodyState::Arguments arguments = state.integratorArguments(kernel);
    arguments.add(state.drudeRelativeEnergies());
    arguments.add(state.drudeRelativeCount());
    arguments.add(length);
    for (int offset : chains)
        arguments.add(offset);
    arguments.add(weights);
    arguments.add((int) w.size());
    arguments.add(integrator.getNumMultiTimeSteps());
    argumentDof = arguments.addMixed(0.0);
    for (int k = 0; k < 6; k++)   // kT, frequency, Drude dof, Drude kT, Drude frequency, half step
        arguments.addMixed(0.0);
}

void CommonIntegrateMRattleDrudeNoseHooverStepKernel::chainsHalfStep(const RigidBodyIntegrator& base) {
    const MRattleDrudeNoseHooverIntegrator& integrator = static_cast<const MRattleDrudeNoseHooverIntegrator&>(base);
    const int drudeDof = 3 * numDrudes;
    const double values[] = {(double) (state.degreesOfFreedom() - drudeDof), BOLTZ * integrator.getTemperature(),
                             integrator.getCollisionFrequency(), (double) drudeDof,
                             BOLTZ * integrator.getDrudeTemperature(), integrator.getDrudeCollisionFrequency(),
                             0.5 * integrator.getStepSize()};
    for (int k = 0; k < 7; k++)
        state.setMixedArg(kernel, argumentDof + k, values[k]);
    state.sumDrudeKineticEnergies();
    state.launch(kernel, CommonRigidBodyState::ReductionThreads, CommonRigidBodyState::ReductionThreads);
    state.scaleDrudeVelocities();
}

void CommonIntegrateMRattleDrudeNoseHooverStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& bound,
                                                              bool& forcesAreValid) {
    const MRattleDrudeNoseHooverIntegrator& integrator = static_cast<const MRattleDrudeNoseHooverIntegrator&>(bound);
    ContextSelector selector(state.computeContext());
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    // The chains' half step, velocity Verlet (MRattleIntegrator's) with the hard wall after the
    // drift, the chains' half step; both chains uncoupled (at rest): MRattleIntegrator's step.
    const bool coupled = integrator.getCollisionFrequency() != 0 || integrator.getDrudeCollisionFrequency() != 0;
    DrudeGroups::requireNumDrudeParticles(context.getSystem(), numDrudes, IntegratorNames::MRattleDrudeNoseHoover.integrator);
    state.beginStep(context, integrator, forcesAreValid);
    if (coupled)
        chainsHalfStep(integrator);
    state.driftAndReset(0.5 * h, h, tolerance);
    state.bounceDrudes(integrator.getMaxDrudeDistance(), integrator.getDrudeTemperature(), h);
    state.computeForces(context, integrator, forcesAreValid);
    state.kick(0.5 * h);
    state.project(tolerance);
    if (coupled)
        chainsHalfStep(integrator);
    state.endStep(h, forcesAreValid);
}

double CommonIntegrateMRattleDrudeNoseHooverStepKernel::computeHeatBathEnergy(ContextImpl& context,
                                                                              const RigidBodyIntegrator& base) {
    const MRattleDrudeNoseHooverIntegrator& integrator = static_cast<const MRattleDrudeNoseHooverIntegrator&>(base);
    const IntegratorParameterValues values = state.getIntegratorParameters(context);
    RigidBodyThermostats::NoseHooverChain chain = RigidBodyThermostats::NoseHooverChain::fromParameters(values);
    RigidBodyThermostats::NoseHooverChain drudeChain;
    drudeChain.positions = values.at("drudeChainPositions");
    drudeChain.velocities = values.at("drudeChainVelocities");
    const int drudeDof = 3 * numDrudes, dof = state.degreesOfFreedom() - drudeDof;
    return chain.energy(dof, BOLTZ * integrator.getTemperature(), integrator.getCollisionFrequency()) +
           drudeChain.energy(drudeDof, BOLTZ * integrator.getDrudeTemperature(),
                             integrator.getDrudeCollisionFrequency());
}

double CommonIntegrateMRattleDrudeNoseHooverStepKernel::computeDrudeKineticEnergy(ContextImpl& context,
                                                                                  int& numDrudeParticles) {
    ContextSelector selector(state.computeContext());
    numDrudeParticles = numDrudes;
    return state.computeDrudeKineticEnergy();
}
