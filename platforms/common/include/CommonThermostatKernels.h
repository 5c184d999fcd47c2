#ifndef MRATTLE_COMMON_THERMOSTAT_KERNELS_H_
#define MRATTLE_COMMON_THERMOSTAT_KERNELS_H_

#include "CommonKernelArguments.h"
#include "CommonRigidBodyStepKernel.h"
#include "MRattleBussiIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "internal/RigidBodyThermostats.h"

namespace MRattlePlugin {

/** The number of work items of each work group of the thermostats' kernels (THERMOSTAT_THREADS in thermostats.cc). */
const int ThermostatThreads = 128;
/** thermostats.cc with its work-group size: what the thermostats append to the step's program. */
std::string thermostatSources();

/**
 * Velocity Verlet with M-RATTLE between two half steps of a thermostat that scales every
 * velocity by one factor, on the common compute platforms, with nothing read back to the
 * host (thermostats.cc): each half step sums the kinetic energy over every work group of the
 * device (sumKineticEnergy()), then one small kernel of the subclass turns the partial sums
 * into the factor; the first half step's scaling is done by the step's first pass, with the
 * step's backup of the atoms, the second's by a kernel across the device. The first half step
 * changes the thermostat's state before that pass, so it backs that state up itself, and
 * CommonStepFailure puts it back with the atoms when a step fails (found lazily).
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
    /**
     * The thermostat's factor for every velocity into the dynamics' velocityScale() (called
     * only when it is coupled): sumKineticEnergy(), then its own kernel, which on the first
     * half step of a step (first) backs up its state.
     */
    virtual void halfStep(const Integrator& integrator, bool first) = 0;
    /**
     * thermostatPartialSums across the device: twice the kinetic energy, and the squares of
     * numGaussians - 1 of OpenMM's Gaussian numbers from randomIndex on (random: null when
     * none are drawn), as partial sums per work group.
     */
    void sumKineticEnergy(OpenMM::ArrayInterface* random = nullptr, unsigned int randomIndex = 0, int numGaussians = 0);
    /** The partial sums' arguments (their array and count), which the subclass's kernel takes first. */
    void addPartialSums(CommonKernelArguments& arguments);
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
    OpenMM::ComputeKernel partialSumsKernel, scaleKernel;
    /** Per work group of thermostatPartialSums: twice the kinetic energy and the Gaussians' squares; and the number of groups. */
    OpenMM::ComputeArray partials, partialCount;
    int argumentPartialsRandomIndex, argumentPartialsGaussians;
    bool sharedArgumentsSet = false;
};

/** MRattleNoseHooverIntegrator on the common compute platforms: the chain lives on the device. */
class CommonIntegrateMRattleNoseHooverStepKernel
    : public CommonVelocityScalingStepKernel<MRattleNoseHooverIntegrator> {
public:
    CommonIntegrateMRattleNoseHooverStepKernel(const std::string& name, const OpenMM::Platform& platform,
                                               OpenMM::ComputeContext& cc)
        : CommonVelocityScalingStepKernel(name, platform, cc) {
    }
    /** Reads the chain from the device (not a per-step cost: only when asked). */
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override;
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override;
    IntegratorParameterValues getIntegratorParameters(OpenMM::ContextImpl& context) override;
    void setIntegratorParameters(OpenMM::ContextImpl& context, const IntegratorParameterValues& values) override;

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
class CommonIntegrateMRattleBussiStepKernel : public CommonVelocityScalingStepKernel<MRattleBussiIntegrator> {
public:
    CommonIntegrateMRattleBussiStepKernel(const std::string& name, const OpenMM::Platform& platform,
                                          OpenMM::ComputeContext& cc)
        : CommonVelocityScalingStepKernel(name, platform, cc) {
    }
    /** Reads the work from the device (only when asked). */
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override;
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override;
    /** The work only: the random stream stays the Context's (replicas must not share one). */
    IntegratorParameterValues getIntegratorParameters(OpenMM::ContextImpl& context) override;
    void setIntegratorParameters(OpenMM::ContextImpl& context, const IntegratorParameterValues& values) override;

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
