#ifndef MRATTLE_COMMON_STEP_KERNELS_H_
#define MRATTLE_COMMON_STEP_KERNELS_H_

#include "CommonRigidBodyState.h"
#include "internal/RigidBodyKernels.h"

namespace MRattlePlugin {

/**
 * The integrators' step kernels on the common compute platforms: each is initialize() and an
 * execute() that lists its phases on the state, as on Reference. Failures are reported by the
 * class name IntegratorNames gives for the kernel's name.
 */
class CommonStepKernel : public RigidBodyStepKernel {
public:
    CommonStepKernel(const std::string& name, const OpenMM::Platform& platform, OpenMM::ComputeContext& cc)
        : RigidBodyStepKernel(name, platform), state(cc, IntegratorNames::ofStepKernel(name).integrator) {
    }
    /** The state alone; an integrator with set-up of its own overrides this. */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override {
        state.initialize(system, topology);
    }
    RigidBodyState& getState() override {
        return state;
    }

protected:
    CommonRigidBodyState state;
};

/** MRattleIntegrator: velocity Verlet with M-RATTLE's resets; two launches a step. */
class CommonIntegrateMRattleStepKernel : public CommonStepKernel {
public:
    using CommonStepKernel::CommonStepKernel;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;
};

/**
 * MRattleLangevinIntegrator: LangevinMiddle's splitting with each drift reset by M-RATTLE and
 * the velocities projected after the kick and after the noise (OpenMM's device random
 * numbers, which its checkpoints hold); two launches a step.
 */
class CommonIntegrateMRattleLangevinStepKernel : public CommonStepKernel {
public:
    using CommonStepKernel::CommonStepKernel;
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;
};

/**
 * Velocity Verlet with M-RATTLE between two half steps of a thermostat that scales every
 * velocity by one factor, which its own kernel computes on the device from the state's
 * kinetic energy sums (kernels/thermostats.cc); seven launches a step when coupled.
 */
class CommonThermostatStepKernel : public CommonStepKernel {
public:
    using CommonStepKernel::CommonStepKernel;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;

protected:
    virtual double collisionFrequency(const RigidBodyIntegrator& integrator) const = 0;
    /** The factor for every velocity into the state's velocity scale (sumKineticEnergy, then the thermostat's kernel). */
    virtual void halfStep(const RigidBodyIntegrator& integrator) = 0;
    OpenMM::ComputeKernel kernel;
};

/** MRattleNoseHooverIntegrator: the chain lives on the device, declared to the state. */
class CommonIntegrateMRattleNoseHooverStepKernel : public CommonThermostatStepKernel {
public:
    using CommonThermostatStepKernel::CommonThermostatStepKernel;
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override;

protected:
    double collisionFrequency(const RigidBodyIntegrator& integrator) const override;
    void halfStep(const RigidBodyIntegrator& integrator) override;

private:
    OpenMM::ComputeArray weights;
    int argumentDof, argumentKT, argumentFrequency, argumentHalfStep;
};

/** MRattleBussiIntegrator: OpenMM's device Gaussian numbers; the work lives on the device, declared to the state. */
class CommonIntegrateMRattleBussiStepKernel : public CommonThermostatStepKernel {
public:
    using CommonThermostatStepKernel::CommonThermostatStepKernel;
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override;

protected:
    double collisionFrequency(const RigidBodyIntegrator& integrator) const override;
    void halfStep(const RigidBodyIntegrator& integrator) override;

private:
    /** OpenMM's random float4s a CSVR half step takes: R_1 and the chi-squared draw's tries (chiSquared). */
    static constexpr int CsvrRandomValues = 16;
    int argumentRandomIndex, argumentDof, argumentKT, argumentC;
};

/**
 * MRattleDrudeLangevinIntegrator: MRattleLangevinIntegrator's step with the noise split between
 * the Drude groups' rigid motion and their Drude particles' relative motion (the state's
 * Drude phases), and the hard wall after the drift.
 */
class CommonIntegrateMRattleDrudeLangevinStepKernel : public CommonStepKernel {
public:
    using CommonStepKernel::CommonStepKernel;
    /** The Drude groups (a Drude particle in a body is refused here) and OpenMM's device random numbers. */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;
    double computeDrudeKineticEnergy(OpenMM::ContextImpl& context, int& numDrudeParticles) override;

private:
    int numDrudes = 0;
};

/**
 * MRattleDrudeNoseHooverIntegrator: two Nose-Hoover chains on the device, one on the Drude
 * groups' rigid motion and the other atoms, one on the Drude particles' relative motion
 * (kernels/thermostats.cc), declared to the state; velocity Verlet with M-RATTLE and the hard
 * wall between their half steps.
 */
class CommonIntegrateMRattleDrudeNoseHooverStepKernel : public CommonStepKernel {
public:
    using CommonStepKernel::CommonStepKernel;
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override;
    double computeDrudeKineticEnergy(OpenMM::ContextImpl& context, int& numDrudeParticles) override;

private:
    /** Both chains over half a step from KE_R and KE_C, then the velocities scaled by their factors. */
    void chainsHalfStep(const RigidBodyIntegrator& integrator);
    OpenMM::ComputeKernel kernel;
    OpenMM::ComputeArray weights;
    int numDrudes = 0;
    int argumentDof;
};

} // namespace MRattlePlugin

#endif
