#include "CommonThermostatKernels.h"
#include "CommonKernelArguments.h"
#include "CommonMRattleKernelSources.h"
#include "openmm/OpenMMException.h"
#include "openmm/common/IntegrationUtilities.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>
#include <sstream>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {
bool doubleMixed(ComputeContext& cc) {
    return cc.getUseDoublePrecision() || cc.getUseMixedPrecision();
}
} // namespace

std::string MRattlePlugin::thermostatSources() {
    return "#define THERMOSTAT_THREADS " + std::to_string(ThermostatThreads) + "\n" + CommonMRattleKernelSources::thermostats;
}

template <class StepKernel>
void CommonVelocityScalingStepKernel<StepKernel>::execute(ContextImpl& context, const Integrator& integrator,
                                                          bool& forcesAreValid) {
    CommonRigidBodyDynamics& dynamics = this->dynamics;
    ContextSelector selector(dynamics.computeContext());
    const double h = integrator.getStepSize();
    // The thermostat's half step, then velocity Verlet (its scaling, half kick, drift and
    // reset: one pass; new forces; half kick and projection: one pass), then the
    // thermostat's second half step. Uncoupled: MRattleIntegrator's step (as on the host).
    const bool coupled = integrator.getCollisionFrequency() != 0;
    dynamics.beginStep(context, integrator, forcesAreValid);
    CommonRigidBodyDynamics::Pass first;
    if (coupled) {
        halfStep(integrator, true);
        first.scaleVelocities = true;
    }
    first.kickTime = 0.5 * h;
    first.driftTime = h;
    dynamics.advance(first);
    dynamics.computeForces(context, integrator, forcesAreValid);
    CommonRigidBodyDynamics::Pass second;
    second.kickTime = 0.5 * h;
    second.projectAfterKick = true;
    dynamics.advance(second);
    if (coupled) {
        halfStep(integrator, false);  // its sumKineticEnergy() has set scaleKernel's arguments
        scaleKernel->execute(dynamics.computeContext().getNumAtoms());
    }
    dynamics.endStep(h, forcesAreValid);
}

template <class StepKernel>
void CommonVelocityScalingStepKernel<StepKernel>::sumKineticEnergy(ArrayInterface* random, unsigned int randomIndex,
                                                                   int numGaussians) {
    ComputeContext& cc = this->dynamics.computeContext();
    if (!sharedArgumentsSet) {
        CommonKernelArguments sums(partialSumsKernel, doubleMixed(cc));
        sums.add(cc.getNumAtoms());
        sums.add(cc.getVelm());
        if (random != nullptr)
            sums.add(*random);
        else
            sums.add(partials);  // unread: no Gaussians
        argumentPartialsRandomIndex = sums.add(0u);
        argumentPartialsGaussians = sums.add(0);
        sums.add(partials);
        sums.add(partialCount);
        CommonKernelArguments scale(scaleKernel, doubleMixed(cc));
        scale.add(cc.getNumAtoms());
        scale.add(cc.getVelm());
        scale.add(this->dynamics.velocityScale());
        scale.add(this->dynamics.failureFlag());
        sharedArgumentsSet = true;
    }
    partialSumsKernel->setArg(argumentPartialsRandomIndex, randomIndex);
    partialSumsKernel->setArg(argumentPartialsGaussians, numGaussians);
    partialSumsKernel->execute(cc.getNumAtoms(), ThermostatThreads);
}

template <class StepKernel>
void CommonVelocityScalingStepKernel<StepKernel>::addPartialSums(CommonKernelArguments& arguments) {
    arguments.add(partials);
    arguments.add(partialCount);
}

template <class StepKernel>
ComputeProgram CommonVelocityScalingStepKernel<StepKernel>::compileThermostats() {
    ComputeContext& cc = this->dynamics.computeContext();
    ComputeProgram program = this->dynamics.compileWith(thermostatSources());
    partialSumsKernel = program->createKernel("thermostatPartialSums");
    scaleKernel = program->createKernel("scaleVelocities");
    // A launch has at most getNumThreadBlocks() work groups (OpenMM's rule, both platforms).
    initializeMixedArray(partials, 2 * cc.getNumThreadBlocks(), "mrattleThermostatPartialSums");
    partialCount.initialize<int>(cc, 1, "mrattleThermostatPartialCount");
    partialCount.upload(vector<int>(1, 0));
    return program;
}

template <class StepKernel>
void CommonVelocityScalingStepKernel<StepKernel>::initializeMixedArray(ComputeArray& array, int size,
                                                                       const std::string& name) {
    ComputeContext& cc = this->dynamics.computeContext();
    array.initialize(cc, size, doubleMixed(cc) ? sizeof(double) : sizeof(float), name);
    uploadMixed(array, vector<double>(size, 0.0));
}

template <class StepKernel>
void CommonVelocityScalingStepKernel<StepKernel>::uploadMixed(ComputeArray& array, const vector<double>& values) {
    array.upload(values, true);  // converted to float in single precision
}

template <class StepKernel>
vector<double> CommonVelocityScalingStepKernel<StepKernel>::downloadMixed(const ComputeArray& array) const {
    vector<double> values(array.getSize());
    if (array.getElementSize() == sizeof(double))
        array.download(values.data());
    else {
        vector<float> single(array.getSize());
        array.download(single.data());
        for (size_t i = 0; i < single.size(); i++)
            values[i] = single[i];
    }
    return values;
}

template class MRattlePlugin::CommonVelocityScalingStepKernel<MRattleNoseHooverIntegrator>;
template class MRattlePlugin::CommonVelocityScalingStepKernel<MRattleBussiIntegrator>;

// ---- Nose-Hoover chain ---------------------------------------------------------------------

void CommonIntegrateMRattleNoseHooverStepKernel::initializeIntegrator(const System& system,
                                                                      const MRattleNoseHooverIntegrator& integrator) {
    const int length = integrator.getChainLength();
    initializeMixedArray(chainPosition, length, "mrattleChainPosition");
    initializeMixedArray(chainVelocity, length, "mrattleChainVelocity");
    initializeMixedArray(positionBackup, length, "mrattleChainPositionBackup");
    initializeMixedArray(velocityBackup, length, "mrattleChainVelocityBackup");
    const vector<double> w = RigidBodyThermostats::yoshidaSuzukiWeights(integrator.getNumYoshidaSuzukiTimeSteps());
    initializeMixedArray(weights, w.size(), "mrattleYoshidaSuzukiWeights");
    uploadMixed(weights, w);
    dynamics.addStepState(chainPosition, positionBackup);
    dynamics.addStepState(chainVelocity, velocityBackup);
    program = compileThermostats();
    chainKernel = program->createKernel("noseHooverChainHalfStep");
}

void CommonIntegrateMRattleNoseHooverStepKernel::halfStep(const MRattleNoseHooverIntegrator& integrator, bool first) {
    ComputeContext& cc = dynamics.computeContext();
    sumKineticEnergy();
    if (!argumentsSet) {
        CommonKernelArguments arguments(chainKernel, doubleMixed(cc));
        addPartialSums(arguments);
        arguments.add(integrator.getChainLength());
        arguments.add(chainPosition);
        arguments.add(chainVelocity);
        arguments.add(weights);
        arguments.add((int) weights.getSize());
        arguments.add(integrator.getNumMultiTimeSteps());
        argumentDof = arguments.addMixed(0.0);
        argumentKT = arguments.addMixed(0.0);
        argumentFrequency = arguments.addMixed(0.0);
        argumentHalfStep = arguments.addMixed(0.0);
        arguments.add(dynamics.velocityScale());
        arguments.add(dynamics.failureFlag());
        argumentBackUp = arguments.add(-1);
        arguments.add(positionBackup);
        arguments.add(velocityBackup);
        argumentStepIndex = arguments.add(0);
        argumentsSet = true;
    }
    dynamics.setMixedArg(chainKernel, argumentDof, degreesOfFreedom());
    dynamics.setMixedArg(chainKernel, argumentKT, BOLTZ * integrator.getTemperature());
    dynamics.setMixedArg(chainKernel, argumentFrequency, integrator.getCollisionFrequency());
    dynamics.setMixedArg(chainKernel, argumentHalfStep, 0.5 * integrator.getStepSize());
    chainKernel->setArg(argumentBackUp, first ? dynamics.stepBackupIndex() : -1);
    chainKernel->setArg(argumentStepIndex, dynamics.failureStepIndex());
    chainKernel->execute(ThermostatThreads, ThermostatThreads);
}

RigidBodyThermostats::NoseHooverChain CommonIntegrateMRattleNoseHooverStepKernel::downloadChain() const {
    RigidBodyThermostats::NoseHooverChain chain;
    chain.positions = downloadMixed(chainPosition);
    chain.velocities = downloadMixed(chainVelocity);
    return chain;
}

double CommonIntegrateMRattleNoseHooverStepKernel::computeHeatBathEnergy(ContextImpl& context,
                                                                        const RigidBodyIntegrator& bound) {
    const MRattleNoseHooverIntegrator& integrator = static_cast<const MRattleNoseHooverIntegrator&>(bound);
    ContextSelector selector(dynamics.computeContext());
    return downloadChain().energy(degreesOfFreedom(), BOLTZ * integrator.getTemperature(),
                                  integrator.getCollisionFrequency());
}

void CommonIntegrateMRattleNoseHooverStepKernel::createCheckpoint(ContextImpl& context, std::ostream& stream) const {
    // The chain first: the base's state (the bodies' geometry) reads to the end.
    downloadChain().write(stream);
    CommonVelocityScalingStepKernel::createCheckpoint(context, stream);
}

void CommonIntegrateMRattleNoseHooverStepKernel::loadCheckpoint(ContextImpl& context, std::istream& stream) {
    ContextSelector selector(dynamics.computeContext());
    RigidBodyThermostats::NoseHooverChain chain(chainPosition.getSize());
    chain.read(stream);
    CommonVelocityScalingStepKernel::loadCheckpoint(context, stream);
    uploadMixed(chainPosition, chain.positions);
    uploadMixed(chainVelocity, chain.velocities);
}

IntegratorParameterValues CommonIntegrateMRattleNoseHooverStepKernel::getIntegratorParameters(ContextImpl& context) {
    ContextSelector selector(dynamics.computeContext());
    return downloadChain().parameters();
}

void CommonIntegrateMRattleNoseHooverStepKernel::setIntegratorParameters(ContextImpl& context,
                                                                         const IntegratorParameterValues& values) {
    ContextSelector selector(dynamics.computeContext());
    const RigidBodyThermostats::NoseHooverChain chain = RigidBodyThermostats::NoseHooverChain::fromParameters(values);
    uploadMixed(chainPosition, chain.positions);  // values read from this precision: exact
    uploadMixed(chainVelocity, chain.velocities);
}

// ---- CSVR ----------------------------------------------------------------------------------

void CommonIntegrateMRattleBussiStepKernel::initializeIntegrator(const System& system,
                                                                 const MRattleBussiIntegrator& integrator) {
    ComputeContext& cc = dynamics.computeContext();
    // Now, as for the Langevin kernel: a new Context must have the generator before loading a checkpoint.
    if (!dynamics.hasAndersenThermostat())
        cc.getIntegrationUtilities().initRandomNumberGenerator(integrator.getRandomNumberSeed());
    initializeMixedArray(work, 1, "mrattleThermostatWork");
    initializeMixedArray(workBackup, 1, "mrattleThermostatWorkBackup");
    dynamics.addStepState(work, workBackup);
    program = compileThermostats();
    rescaleKernel = program->createKernel("stochasticRescalingHalfStep");
}

void CommonIntegrateMRattleBussiStepKernel::halfStep(const MRattleBussiIntegrator& integrator, bool first) {
    ComputeContext& cc = dynamics.computeContext();
    IntegrationUtilities& integration = cc.getIntegrationUtilities();
    // dof Gaussian numbers: at most 3 per atom, so the 4 per padded atom of one draw suffice.
    const int dof = degreesOfFreedom();
    const unsigned int randomIndex = integration.prepareRandomNumbers(cc.getPaddedNumAtoms());
    sumKineticEnergy(&integration.getRandom(), randomIndex, dof);
    if (!argumentsSet) {
        CommonKernelArguments arguments(rescaleKernel, doubleMixed(cc));
        addPartialSums(arguments);
        arguments.add(integration.getRandom());
        argumentRandomIndex = arguments.add(0u);
        argumentDof = arguments.add(0);
        argumentKT = arguments.addMixed(0.0);
        argumentC = arguments.addMixed(0.0);
        arguments.add(work);
        arguments.add(dynamics.velocityScale());
        arguments.add(dynamics.failureFlag());
        argumentBackUp = arguments.add(-1);
        arguments.add(workBackup);
        argumentStepIndex = arguments.add(0);
        argumentsSet = true;
    }
    rescaleKernel->setArg(argumentRandomIndex, randomIndex);
    rescaleKernel->setArg(argumentDof, dof);
    dynamics.setMixedArg(rescaleKernel, argumentKT, BOLTZ * integrator.getTemperature());
    dynamics.setMixedArg(rescaleKernel, argumentC, std::exp(-integrator.getCollisionFrequency() * 0.5 * integrator.getStepSize()));
    rescaleKernel->setArg(argumentBackUp, first ? dynamics.stepBackupIndex() : -1);
    rescaleKernel->setArg(argumentStepIndex, dynamics.failureStepIndex());
    rescaleKernel->execute(ThermostatThreads, ThermostatThreads);
}

double CommonIntegrateMRattleBussiStepKernel::computeHeatBathEnergy(ContextImpl& context,
                                                                   const RigidBodyIntegrator& integrator) {
    ContextSelector selector(dynamics.computeContext());
    return -downloadMixed(work)[0];
}

void CommonIntegrateMRattleBussiStepKernel::createCheckpoint(ContextImpl& context, std::ostream& stream) const {
    // The work first: the base's state (the bodies' geometry) reads to the end. The random
    // stream is OpenMM's, in OpenMM's part of the checkpoint.
    RigidBodyThermostats::writeCsvrWork(stream, downloadMixed(work)[0]);
    CommonVelocityScalingStepKernel::createCheckpoint(context, stream);
}

void CommonIntegrateMRattleBussiStepKernel::loadCheckpoint(ContextImpl& context, std::istream& stream) {
    ContextSelector selector(dynamics.computeContext());
    const double value = RigidBodyThermostats::readCsvrWork(stream);
    CommonVelocityScalingStepKernel::loadCheckpoint(context, stream);
    uploadMixed(work, vector<double>(1, value));
}

IntegratorParameterValues CommonIntegrateMRattleBussiStepKernel::getIntegratorParameters(ContextImpl& context) {
    ContextSelector selector(dynamics.computeContext());
    return RigidBodyThermostats::csvrParameters(downloadMixed(work)[0]);
}

void CommonIntegrateMRattleBussiStepKernel::setIntegratorParameters(ContextImpl& context,
                                                                    const IntegratorParameterValues& values) {
    ContextSelector selector(dynamics.computeContext());
    uploadMixed(work, vector<double>(1, RigidBodyThermostats::csvrWork(values)));
}
