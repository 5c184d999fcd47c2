#include "ReferenceThermostatKernels.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <sstream>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

template <class StepKernel>
void ReferenceVelocityScalingStepKernel<StepKernel>::execute(ContextImpl& context, const Integrator& integrator,
                                                             bool& forcesAreValid) {
    ReferenceRigidBodyDynamics& dynamics = this->dynamics;
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    // The thermostat's half step, then velocity Verlet (half kick, drift and reset, new
    // forces, half kick and projection), then the thermostat's second half step.
    dynamics.beginStep(context, integrator, forcesAreValid);
    backUpState();
    try {
        halfStep(integrator);
        dynamics.driftAndReset(0.5 * h, h, tolerance);
        dynamics.computeForces(context, integrator, forcesAreValid);
        dynamics.kick(0.5 * h);
        dynamics.project(tolerance, false);
        halfStep(integrator);
        dynamics.endStep(h, forcesAreValid);
    } catch (...) {
        restoreState();  // the particles are put back by the phase that failed; the thermostat here
        throw;
    }
}

template <class StepKernel>
void ReferenceVelocityScalingStepKernel<StepKernel>::halfStep(const Integrator& integrator) {
    vector<Vec3>& v = this->dynamics.velocities();
    const double scale = halfStepScale(this->dynamics.operations().kineticEnergy(v), integrator);
    for (Vec3& velocity : v)
        velocity *= scale;
}

// The two thermostats' instances (the kernels that derive from them are defined below).
template class MRattlePlugin::ReferenceVelocityScalingStepKernel<MRattleNoseHooverIntegrator>;
template class MRattlePlugin::ReferenceVelocityScalingStepKernel<MRattleBussiIntegrator>;

// ---- Nose-Hoover chain ---------------------------------------------------------------------

void ReferenceIntegrateMRattleNoseHooverStepKernel::initializeIntegrator(const System& system,
                                                                         const MRattleNoseHooverIntegrator& integrator) {
    chain = RigidBodyThermostats::NoseHooverChain(integrator.getChainLength());
}

double ReferenceIntegrateMRattleNoseHooverStepKernel::halfStepScale(double kineticEnergy,
                                                                    const MRattleNoseHooverIntegrator& integrator) {
    return chain.propagate(kineticEnergy, degreesOfFreedom(), BOLTZ * integrator.getTemperature(),
                           integrator.getCollisionFrequency(), 0.5 * integrator.getStepSize(),
                           integrator.getNumMultiTimeSteps(),
                           RigidBodyThermostats::yoshidaSuzukiWeights(integrator.getNumYoshidaSuzukiTimeSteps()));
}

double ReferenceIntegrateMRattleNoseHooverStepKernel::computeHeatBathEnergy(ContextImpl& context,
                                                                           const RigidBodyIntegrator& bound) {
    const MRattleNoseHooverIntegrator& integrator = static_cast<const MRattleNoseHooverIntegrator&>(bound);
    return chain.energy(degreesOfFreedom(), BOLTZ * integrator.getTemperature(), integrator.getCollisionFrequency());
}

void ReferenceIntegrateMRattleNoseHooverStepKernel::createCheckpoint(ContextImpl& context, std::ostream& stream) const {
    // The chain first: the base's state (a text random state) reads to the end.
    chain.write(stream);
    ReferenceVelocityScalingStepKernel::createCheckpoint(context, stream);
}

void ReferenceIntegrateMRattleNoseHooverStepKernel::loadCheckpoint(ContextImpl& context, std::istream& stream) {
    chain.read(stream);
    ReferenceVelocityScalingStepKernel::loadCheckpoint(context, stream);
}

// ---- CSVR ----------------------------------------------------------------------------------

void ReferenceIntegrateMRattleBussiStepKernel::initializeIntegrator(const System& system,
                                                                    const MRattleBussiIntegrator& integrator) {
    dynamics.operations().seedRandom(integrator.getRandomNumberSeed());
    work = 0;
}

double ReferenceIntegrateMRattleBussiStepKernel::halfStepScale(double kineticEnergy,
                                                               const MRattleBussiIntegrator& integrator) {
    const double scale = RigidBodyThermostats::csvrScale(kineticEnergy, degreesOfFreedom(),
                                                         BOLTZ * integrator.getTemperature(),
                                                         integrator.getCollisionFrequency(),
                                                         0.5 * integrator.getStepSize(), dynamics.operations().random());
    work += (scale * scale - 1) * kineticEnergy;
    return scale;
}

void ReferenceIntegrateMRattleBussiStepKernel::createCheckpoint(ContextImpl& context, std::ostream& stream) const {
    // The work first: the base's state (the random stream, as text) reads to the end.
    RigidBodyThermostats::writeCsvrWork(stream, work);
    ReferenceVelocityScalingStepKernel::createCheckpoint(context, stream);
}

void ReferenceIntegrateMRattleBussiStepKernel::loadCheckpoint(ContextImpl& context, std::istream& stream) {
    const double checkpointWork = RigidBodyThermostats::readCsvrWork(stream);
    ReferenceVelocityScalingStepKernel::loadCheckpoint(context, stream);
    work = checkpointWork;
}
