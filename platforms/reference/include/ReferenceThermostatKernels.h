#ifndef MRATTLE_REFERENCE_THERMOSTAT_KERNELS_H_
#define MRATTLE_REFERENCE_THERMOSTAT_KERNELS_H_

#include "MRattleBussiIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "ReferenceRigidBodyStepKernel.h"
#include "internal/RigidBodyKernels.h"
#include "internal/RigidBodyThermostats.h"
#include <random>

namespace MRattlePlugin {

/**
 * Velocity Verlet with M-RATTLE between two half steps of a thermostat that scales every
 * velocity by one factor (the Nose-Hoover chain, CSVR), on the Reference and CPU platforms;
 * execute() reads line for line like CommonVelocityScalingStepKernel's. The thermostat's
 * state is copied at the start of each step and put back if the step fails, as the
 * particles are. A subclass supplies the factor over half a step and the state.
 */
template <class StepKernel>
class ReferenceVelocityScalingStepKernel : public ReferenceRigidBodyStepKernel<StepKernel> {
public:
    typedef ReferenceRigidBodyStepKernel<StepKernel> Base;
    typedef typename Base::Integrator Integrator;
    using Base::Base;
    void execute(OpenMM::ContextImpl& context, const Integrator& integrator, bool& forcesAreValid) override;

protected:
    /** The thermostat over half a step at this kinetic energy: the factor that scales every velocity. */
    virtual double halfStepScale(double kineticEnergy, const Integrator& integrator) = 0;
    /** Copy the thermostat's state aside, or put the copy back. */
    virtual void backUpState() = 0;
    virtual void restoreState() = 0;
    /** The System's degrees of freedom, by the plugin's rule (RigidBodyTopology). */
    double degreesOfFreedom() {
        return this->dynamics.operations().topology().getNumDegreesOfFreedom(this->dynamics.bodyDegreesOfFreedom());
    }

private:
    /** The thermostat's half step: every velocity scaled by halfStepScale(). */
    void halfStep(const Integrator& integrator);
};

/** MRattleNoseHooverIntegrator on the Reference platform, also registered on the CPU platform. */
class ReferenceIntegrateMRattleNoseHooverStepKernel
    : public ReferenceVelocityScalingStepKernel<MRattleNoseHooverIntegrator> {
public:
    using ReferenceVelocityScalingStepKernel::ReferenceVelocityScalingStepKernel;
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override;
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override;
    IntegratorParameterValues getIntegratorParameters(OpenMM::ContextImpl& context) override {
        return chain.parameters();
    }
    void setIntegratorParameters(OpenMM::ContextImpl& context, const IntegratorParameterValues& values) override {
        chain = RigidBodyThermostats::NoseHooverChain::fromParameters(values);
    }

protected:
    /** A chain of the integrator's length, at rest. */
    void initializeIntegrator(const OpenMM::System& system, const MRattleNoseHooverIntegrator& integrator) override;
    double halfStepScale(double kineticEnergy, const MRattleNoseHooverIntegrator& integrator) override;
    void backUpState() override {
        savedChain = chain;
    }
    void restoreState() override {
        chain = savedChain;
    }

private:
    RigidBodyThermostats::NoseHooverChain chain, savedChain;
};

/** MRattleBussiIntegrator on the Reference platform, also registered on the CPU platform. */
class ReferenceIntegrateMRattleBussiStepKernel : public ReferenceVelocityScalingStepKernel<MRattleBussiIntegrator> {
public:
    using ReferenceVelocityScalingStepKernel::ReferenceVelocityScalingStepKernel;
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override {
        return -work;
    }
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override;
    /** The work only: the random stream stays the Context's (replicas must not share one). */
    IntegratorParameterValues getIntegratorParameters(OpenMM::ContextImpl& context) override {
        return RigidBodyThermostats::csvrParameters(work);
    }
    void setIntegratorParameters(OpenMM::ContextImpl& context, const IntegratorParameterValues& values) override {
        work = RigidBodyThermostats::csvrWork(values);
    }

protected:
    /** The stream seeded now (so a checkpoint before the first step holds it); no work yet. */
    void initializeIntegrator(const OpenMM::System& system, const MRattleBussiIntegrator& integrator) override;
    double halfStepScale(double kineticEnergy, const MRattleBussiIntegrator& integrator) override;
    void backUpState() override {
        savedRandom = dynamics.operations().random();
        savedWork = work;
    }
    void restoreState() override {
        dynamics.operations().random() = savedRandom;
        work = savedWork;
    }

private:
    /** The kinetic energy the rescalings have added to the System (kJ/mol). */
    double work = 0, savedWork = 0;
    std::mt19937_64 savedRandom;
};

} // namespace MRattlePlugin

#endif
