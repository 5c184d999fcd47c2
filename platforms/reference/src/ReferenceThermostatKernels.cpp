#include "ReferenceThermostatKernels.h"
#include "HostRigidBodyRules.h"
#include "openmm/OpenMMException.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>
#include <sstream>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

template <class StepKernel>
void ReferenceVelocityScalingStepKernel<StepKernel>::integratePositions(ContextImpl& context,
                                                                       const Integrator& integrator) {
    vector<Vec3>& x = ReferenceRigidBodyDynamics::positions(context);
    vector<Vec3>& v = ReferenceRigidBodyDynamics::velocities(context);
    const vector<Vec3>& f = ReferenceRigidBodyDynamics::forces(context);
    const double h = integrator.getStepSize();
    // The thermostat's first half step on a copy: the Context keeps v until the step is known to be good.
    const double scale = halfStepScale(this->dynamics->kineticEnergy(v), integrator);
    scaled.resize(v.size());
    for (size_t i = 0; i < v.size(); i++)
        scaled[i] = v[i] * scale;
    this->dynamics->driftAndReset(x, scaled, h, integrator.getConstraintTolerance(), this->newPositions,
                                  this->newVelocities, &f, 0.5 * h);
    x.swap(this->newPositions);
    // newVelocities keeps the unscaled velocities from before the step, for execute() to undo it.
    v.swap(this->newVelocities);
    this->placeVirtualSites(context);
}

template <class StepKernel>
void ReferenceVelocityScalingStepKernel<StepKernel>::finishStep(ContextImpl& context, const Integrator& integrator) {
    Base::finishStep(context, integrator);  // velocity Verlet's closing half kick and projection
    vector<Vec3>& v = ReferenceRigidBodyDynamics::velocities(context);
    const double scale = halfStepScale(this->dynamics->kineticEnergy(v), integrator);
    for (Vec3& velocity : v)
        velocity *= scale;
}

// The two thermostats' instances (the kernels that derive from them are defined below).
template class MRattlePlugin::ReferenceVelocityScalingStepKernel<IntegrateMRattleNoseHooverStepKernel>;
template class MRattlePlugin::ReferenceVelocityScalingStepKernel<IntegrateMRattleBussiStepKernel>;

// ---- Nose-Hoover chain ---------------------------------------------------------------------

void ReferenceIntegrateMRattleNoseHooverStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                               const RigidBodyIntegrator& integrator) {
    ReferenceVelocityScalingStepKernel::initialize(system, topology, integrator);
    chain = RigidBodyThermostats::NoseHooverChain(
        static_cast<const MRattleNoseHooverIntegrator&>(integrator).getChainLength());
}

double ReferenceIntegrateMRattleNoseHooverStepKernel::halfStepScale(double kineticEnergy,
                                                                    const MRattleNoseHooverIntegrator& integrator) {
    return chain.propagate(kineticEnergy, degreesOfFreedom(), BOLTZ * integrator.getTemperature(),
                           integrator.getCollisionFrequency(), 0.5 * integrator.getStepSize(),
                           integrator.getNumMultiTimeSteps(),
                           RigidBodyThermostats::yoshidaSuzukiWeights(integrator.getNumYoshidaSuzukiTimeSteps()));
}

double ReferenceIntegrateMRattleNoseHooverStepKernel::computeHeatBathEnergy(ContextImpl& context,
                                                                           const MRattleNoseHooverIntegrator& integrator) {
    return chain.energy(degreesOfFreedom(), BOLTZ * integrator.getTemperature(), integrator.getCollisionFrequency());
}

void ReferenceIntegrateMRattleNoseHooverStepKernel::createCheckpoint(ContextImpl& context, std::ostream& stream) const {
    ReferenceVelocityScalingStepKernel::createCheckpoint(context, stream);
    std::ostringstream state;
    chain.write(state);
    HostRigidBodyRules::writeKernelState(stream, state.str());
}

void ReferenceIntegrateMRattleNoseHooverStepKernel::loadCheckpoint(ContextImpl& context, std::istream& stream) {
    ReferenceVelocityScalingStepKernel::loadCheckpoint(context, stream);
    std::istringstream state(HostRigidBodyRules::readKernelState(stream));
    chain.read(state);
}

// ---- CSVR ----------------------------------------------------------------------------------

void ReferenceIntegrateMRattleBussiStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                          const RigidBodyIntegrator& integrator) {
    ReferenceVelocityScalingStepKernel::initialize(system, topology, integrator);
    dynamics->seedRandom(static_cast<const MRattleBussiIntegrator&>(integrator).getRandomNumberSeed());
    work = 0;
}

double ReferenceIntegrateMRattleBussiStepKernel::halfStepScale(double kineticEnergy,
                                                               const MRattleBussiIntegrator& integrator) {
    const double scale = RigidBodyThermostats::csvrScale(kineticEnergy, degreesOfFreedom(),
                                                         BOLTZ * integrator.getTemperature(),
                                                         integrator.getCollisionFrequency(),
                                                         0.5 * integrator.getStepSize(), dynamics->random());
    work += (scale * scale - 1) * kineticEnergy;
    return scale;
}

void ReferenceIntegrateMRattleBussiStepKernel::createCheckpoint(ContextImpl& context, std::ostream& stream) const {
    ReferenceVelocityScalingStepKernel::createCheckpoint(context, stream);  // the random stream (on a device, OpenMM's part holds it)
    HostRigidBodyRules::writeKernelState(stream, RigidBodyThermostats::csvrWorkState(work));
}

void ReferenceIntegrateMRattleBussiStepKernel::loadCheckpoint(ContextImpl& context, std::istream& stream) {
    ReferenceVelocityScalingStepKernel::loadCheckpoint(context, stream);
    const double value = RigidBodyThermostats::csvrWorkFromState(HostRigidBodyRules::readKernelState(stream));
    work = value;
}
