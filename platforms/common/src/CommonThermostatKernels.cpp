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
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    // The thermostat's half step, then velocity Verlet (half kick, drift and reset, new
    // forces, half kick and projection), then the thermostat's second half step.
    dynamics.beginStep(context, integrator, forcesAreValid);
    halfStep(integrator, true);
    dynamics.driftAndReset(0.5 * h, h, tolerance);
    dynamics.computeForces(context, integrator, forcesAreValid);
    dynamics.kick(0.5 * h);
    dynamics.project(tolerance, false);
    halfStep(integrator, false);
    dynamics.endStep(h, forcesAreValid);
}

template <class StepKernel>
ComputeProgram CommonVelocityScalingStepKernel<StepKernel>::compileThermostats() {
    return this->dynamics.compileWith(thermostatSources());
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

template class MRattlePlugin::CommonVelocityScalingStepKernel<IntegrateMRattleNoseHooverStepKernel>;
template class MRattlePlugin::CommonVelocityScalingStepKernel<IntegrateMRattleBussiStepKernel>;

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
    if (integrator.getCollisionFrequency() == 0)
        return;  // the chain does not move: MRattleIntegrator's step (as on the host)
    ComputeContext& cc = dynamics.computeContext();
    if (!argumentsSet) {
        CommonKernelArguments arguments(chainKernel, doubleMixed(cc));
        arguments.add(cc.getNumAtoms());
        arguments.add(cc.getVelm());
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
        arguments.add(dynamics.failureFlag());
        dynamics.addBackupArguments(arguments);
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
    chainKernel->setArg(argumentBackUp, first ? dynamics.takeStepBackup() : -1);
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
                                                                        const MRattleNoseHooverIntegrator& integrator) {
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
    if (integrator.getCollisionFrequency() == 0)
        return;  // no coupling: MRattleIntegrator's step, nothing drawn (as on the host)
    ComputeContext& cc = dynamics.computeContext();
    IntegrationUtilities& integration = cc.getIntegrationUtilities();
    if (!argumentsSet) {
        CommonKernelArguments arguments(rescaleKernel, doubleMixed(cc));
        arguments.add(cc.getNumAtoms());
        arguments.add(cc.getVelm());
        arguments.add(integration.getRandom());
        argumentRandomIndex = arguments.add(0u);
        argumentDof = arguments.add(0);
        argumentKT = arguments.addMixed(0.0);
        argumentC = arguments.addMixed(0.0);
        arguments.add(work);
        arguments.add(dynamics.failureFlag());
        dynamics.addBackupArguments(arguments);
        argumentBackUp = arguments.add(-1);
        arguments.add(workBackup);
        argumentStepIndex = arguments.add(0);
        argumentsSet = true;
    }
    // dof Gaussian numbers: at most 3 per atom, so the 4 per padded atom of one draw suffice.
    const int dof = degreesOfFreedom();
    rescaleKernel->setArg(argumentRandomIndex, (unsigned int) integration.prepareRandomNumbers(cc.getPaddedNumAtoms()));
    rescaleKernel->setArg(argumentDof, dof);
    dynamics.setMixedArg(rescaleKernel, argumentKT, BOLTZ * integrator.getTemperature());
    dynamics.setMixedArg(rescaleKernel, argumentC, std::exp(-integrator.getCollisionFrequency() * 0.5 * integrator.getStepSize()));
    rescaleKernel->setArg(argumentBackUp, first ? dynamics.takeStepBackup() : -1);
    rescaleKernel->setArg(argumentStepIndex, dynamics.failureStepIndex());
    rescaleKernel->execute(ThermostatThreads, ThermostatThreads);
}

double CommonIntegrateMRattleBussiStepKernel::computeHeatBathEnergy(ContextImpl& context) {
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
