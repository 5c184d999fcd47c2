#ifndef MRATTLE_COMMON_THERMOSTAT_KERNELS_H_
#define MRATTLE_COMMON_THERMOSTAT_KERNELS_H_

#include "CommonRigidBodyStepKernel.h"
#include "MRattleBussiIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "internal/RigidBodyThermostats.h"

namespace MRattlePlugin {

/** The number of work items of the thermostat's work group (THERMOSTAT_THREADS in thermostats.cc). */
const int ThermostatThreads = 128;
/** thermostats.cc with its work-group size: what the thermostats append to the step's program. */
std::string thermostatSources();

/**
 * Velocity Verlet with M-RATTLE between two half steps of a thermostat that scales every
 * velocity by one factor, on the common compute platforms: the thermostat's half step is
 * one device kernel (thermostats.cc) that sums the kinetic energy, computes the factor and
 * scales, so no step reads anything back to the host. The first half step of each step
 * changes the state before the step's first pass, so it makes the step's backup (the atoms'
 * and the thermostat's) while the failure flag is clear, and CommonStepFailure puts both
 * back when a step fails (found lazily).
 * A subclass supplies the half step and the state.
 */
template <class StepKernel>
class CommonVelocityScalingStepKernel : public CommonRigidBodyStepKernel<StepKernel> {
public:
    typedef CommonRigidBodyStepKernel<StepKernel> Base;
    typedef typename Base::Integrator Integrator;
    using Base::Base;
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override {
        bodies = topology;
        Base::initialize(system, topology, integrator);
    }
    void execute(OpenMM::ContextImpl& context, const Integrator& integrator, bool& forcesAreValid) override;

protected:
    /** The thermostat's half step on the device (nothing when it is uncoupled); the first backs up its state. */
    virtual void halfStep(const Integrator& integrator, bool first) = 0;
    /** The System's degrees of freedom, by the plugin's rule (RigidBodyTopology). */
    int degreesOfFreedom() const {
        return bodies.getNumDegreesOfFreedom(this->dynamics.bodyDegreesOfFreedom());
    }
    /** thermostats.cc compiled with the step's program. */
    OpenMM::ComputeProgram compileThermostats();
    /** A device array of this many numbers in the integration arithmetic's precision ('mixed'). */
    void initializeMixedArray(OpenMM::ComputeArray& array, int size, const std::string& name);
    /** Upload to, or download from, such an array. */
    void uploadMixed(OpenMM::ComputeArray& array, const std::vector<double>& values);
    std::vector<double> downloadMixed(const OpenMM::ComputeArray& array) const;

private:
    RigidBodyTopology bodies;
};

/** MRattleNoseHooverIntegrator on the common compute platforms: the chain lives on the device. */
class CommonIntegrateMRattleNoseHooverStepKernel
    : public CommonVelocityScalingStepKernel<IntegrateMRattleNoseHooverStepKernel> {
public:
    CommonIntegrateMRattleNoseHooverStepKernel(const std::string& name, const OpenMM::Platform& platform,
                                               OpenMM::ComputeContext& cc)
        : CommonVelocityScalingStepKernel(name, platform, cc) {
    }
    /** Reads the chain from the device (not a per-step cost: only when asked). */
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const MRattleNoseHooverIntegrator& integrator) override;
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override;

protected:
    void initializeIntegrator(const OpenMM::System& system, const MRattleNoseHooverIntegrator& integrator) override;
    void halfStep(const MRattleNoseHooverIntegrator& integrator, bool first) override;

private:
    /** The chain as the host code holds it, from the device. */
    RigidBodyThermostats::NoseHooverChain downloadChain() const;
    OpenMM::ComputeProgram program;
    OpenMM::ComputeKernel chainKernel;
    OpenMM::ComputeArray chainPosition, chainVelocity, positionBackup, velocityBackup, weights;
    int argumentDof, argumentKT, argumentFrequency, argumentHalfStep, argumentBackUp, argumentStepIndex;
    bool argumentsSet = false;
};

/** MRattleBussiIntegrator on the common compute platforms: OpenMM's device Gaussian numbers, the work on the device. */
class CommonIntegrateMRattleBussiStepKernel : public CommonVelocityScalingStepKernel<IntegrateMRattleBussiStepKernel> {
public:
    CommonIntegrateMRattleBussiStepKernel(const std::string& name, const OpenMM::Platform& platform,
                                          OpenMM::ComputeContext& cc)
        : CommonVelocityScalingStepKernel(name, platform, cc) {
    }
    /** Reads the work from the device (only when asked). */
    double computeHeatBathEnergy(OpenMM::ContextImpl& context) override;
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override;

protected:
    void initializeIntegrator(const OpenMM::System& system, const MRattleBussiIntegrator& integrator) override;
    void halfStep(const MRattleBussiIntegrator& integrator, bool first) override;

private:
    OpenMM::ComputeProgram program;
    OpenMM::ComputeKernel rescaleKernel;
    OpenMM::ComputeArray work, workBackup;
    int argumentRandomIndex, argumentDof, argumentKT, argumentC, argumentBackUp, argumentStepIndex;
    bool argumentsSet = false;
};

} // namespace MRattlePlugin

#endif
