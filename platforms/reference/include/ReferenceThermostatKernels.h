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
 * velocity by one factor (the Nose-Hoover chain, CSVR) on the Reference and CPU platforms:
 * scale, half kick, drift and reset, forces, half kick and projection, scale. A subclass
 * supplies the factor over half a step and saves and restores its state, so that a failed
 * step leaves the thermostat as it was (as the step contract leaves the particles).
 */
template <class StepKernel>
class ReferenceVelocityScalingStepKernel : public ReferenceRigidBodyStepKernel<StepKernel> {
public:
    typedef ReferenceRigidBodyStepKernel<StepKernel> Base;
    typedef typename Base::Integrator Integrator;
    using Base::Base;
    void execute(OpenMM::ContextImpl& context, const Integrator& integrator, bool& forcesAreValid) override {
        saveThermostat();
        try {
            Base::execute(context, integrator, forcesAreValid);
        } catch (...) {
            restoreThermostat();
            throw;
        }
    }

protected:
    /** The thermostat over half a step at this kinetic energy: the factor that scales every velocity. */
    virtual double halfStepScale(double kineticEnergy, const Integrator& integrator) = 0;
    virtual void saveThermostat() = 0;
    virtual void restoreThermostat() = 0;
    /** The System's degrees of freedom, by the plugin's rule (RigidBodyTopology). */
    double degreesOfFreedom() const {
        return this->dynamics->topology().getNumDegreesOfFreedom(this->dynamics->getBodyDegreesOfFreedom());
    }
    void integratePositions(OpenMM::ContextImpl& context, const Integrator& integrator) override;
    void finishStep(OpenMM::ContextImpl& context, const Integrator& integrator) override;

private:
    std::vector<OpenMM::Vec3> scaled;  // step buffer: the velocities after the first half step of the thermostat
};

/** MRattleNoseHooverIntegrator on the Reference platform, also registered on the CPU platform. */
class ReferenceIntegrateMRattleNoseHooverStepKernel
    : public ReferenceVelocityScalingStepKernel<IntegrateMRattleNoseHooverStepKernel> {
public:
    using ReferenceVelocityScalingStepKernel::ReferenceVelocityScalingStepKernel;
    /** The shared set-up, then a chain of the integrator's length at rest. */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const MRattleNoseHooverIntegrator& integrator) override;
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override;

protected:
    double halfStepScale(double kineticEnergy, const MRattleNoseHooverIntegrator& integrator) override;
    void saveThermostat() override {
        savedChain = chain;
    }
    void restoreThermostat() override {
        chain = savedChain;
    }
    const char* integratorName() const override {
        return "MRattleNoseHooverIntegrator";
    }

private:
    RigidBodyThermostats::NoseHooverChain chain, savedChain;
};

/** MRattleBussiIntegrator on the Reference platform, also registered on the CPU platform. */
class ReferenceIntegrateMRattleBussiStepKernel : public ReferenceVelocityScalingStepKernel<IntegrateMRattleBussiStepKernel> {
public:
    using ReferenceVelocityScalingStepKernel::ReferenceVelocityScalingStepKernel;
    /** The shared set-up, then the stream seeded now (so a checkpoint before the first step holds it). */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    double computeHeatBathEnergy(OpenMM::ContextImpl& context) override {
        return -work;
    }
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override;

protected:
    double halfStepScale(double kineticEnergy, const MRattleBussiIntegrator& integrator) override;
    void saveThermostat() override {
        savedRandom = dynamics->random();
        savedWork = work;
    }
    void restoreThermostat() override {
        dynamics->random() = savedRandom;
        work = savedWork;
    }
    const char* integratorName() const override {
        return "MRattleBussiIntegrator";
    }

private:
    /** The kinetic energy the rescalings have added to the System (kJ/mol). */
    double work = 0, savedWork = 0;
    std::mt19937_64 savedRandom;
};

} // namespace MRattlePlugin

#endif
