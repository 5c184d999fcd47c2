#ifndef MRATTLE_REFERENCE_RIGID_BODY_KERNELS_H_
#define MRATTLE_REFERENCE_RIGID_BODY_KERNELS_H_

#include "MRattleBussiIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "ReferenceRigidBodyState.h"
#include "internal/RigidBodyKernels.h"
#include "internal/RigidBodyThermostats.h"
#include <vector>

namespace MRattlePlugin {

/**
 * A step kernel of the Reference platform, also registered on the CPU platform: its
 * ReferenceRigidBodyState, which the API asks for everything but the step. Each kernel below
 * is initialize() and an execute() listing the phases of that state.
 */
class ReferenceStepKernel : public RigidBodyStepKernel {
public:
    ReferenceStepKernel(const std::string& name, const OpenMM::Platform& platform)
        : RigidBodyStepKernel(name, platform), state(name) {
    }
    RigidBodyState& getState() override {
        return state;
    }

protected:
    ReferenceRigidBodyState state;
};

/** MRattleIntegrator: velocity Verlet with M-RATTLE's resets. */
class ReferenceIntegrateMRattleStepKernel : public ReferenceStepKernel {
public:
    using ReferenceStepKernel::ReferenceStepKernel;
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;
};

/**
 * MRattleLangevinIntegrator: LangevinMiddle's splitting with each drift reset by M-RATTLE and
 * the velocities projected after the kick and after the noise. Leapfrog: the velocities it
 * keeps are those of the middle of the step.
 */
class ReferenceIntegrateMRattleLangevinStepKernel : public ReferenceStepKernel {
public:
    using ReferenceStepKernel::ReferenceStepKernel;
    /** The noise's stream is seeded now, so that a checkpoint before the first step holds it. */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;
};

/**
 * A velocity-scaling thermostat (Nose-Hoover, CSVR): velocity Verlet with M-RATTLE between two
 * half steps of the thermostat, each a factor by which the state scales every velocity.
 */
class ReferenceThermostatStepKernel : public ReferenceStepKernel {
public:
    using ReferenceStepKernel::ReferenceStepKernel;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;

protected:
    /** The thermostat over half a step at the current kinetic energy: the factor for every velocity. */
    virtual double halfStepFactor(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) = 0;
};

/** MRattleNoseHooverIntegrator: a chain's half steps. */
class ReferenceIntegrateMRattleNoseHooverStepKernel : public ReferenceThermostatStepKernel {
public:
    using ReferenceThermostatStepKernel::ReferenceThermostatStepKernel;
    /** A chain of the integrator's length, at rest, declared to the state. */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override;

protected:
    double halfStepFactor(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override;

private:
    RigidBodyThermostats::NoseHooverChain chain;
};

/** MRattleBussiIntegrator: stochastic velocity rescalings (CSVR) as the half steps. */
class ReferenceIntegrateMRattleBussiStepKernel : public ReferenceThermostatStepKernel {
public:
    using ReferenceThermostatStepKernel::ReferenceThermostatStepKernel;
    /** The stream seeded now (so that a checkpoint before the first step holds it); no work yet. */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    /** Minus the work of the rescalings. */
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override {
        return -work[0];
    }

protected:
    /** One rescaling; its work is added up. */
    double halfStepFactor(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override;

private:
    std::vector<double> work = {0.0};   // the kinetic energy the rescalings have added (kJ/mol)
};

/** RigidSplittingIntegrator (the baseline): velocity Verlet, its position update a free-rotor splitting per body. */
class ReferenceIntegrateRigidSplittingStepKernel : public ReferenceStepKernel {
public:
    using ReferenceStepKernel::ReferenceStepKernel;
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;
};

/**
 * MRattleDrudeLangevinIntegrator: MRattleLangevinIntegrator's step, its noise split between
 * the Drude groups' rigid motion and the Drude particles' relative motion, and the hard wall
 * after the drift.
 */
class ReferenceIntegrateMRattleDrudeLangevinStepKernel : public ReferenceStepKernel {
public:
    using ReferenceStepKernel::ReferenceStepKernel;
    /** The Drude groups (a Drude particle in a body is refused here) and the noise's stream. */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;
    double computeDrudeKineticEnergy(OpenMM::ContextImpl& context, int& numDrudeParticles) override;

private:
    DrudeGroups groups;
};

/**
 * MRattleDrudeNoseHooverIntegrator: the two chains' half steps (on KE_R and KE_C), velocity
 * Verlet with M-RATTLE and the hard wall after the drift, the chains' half steps.
 */
class ReferenceIntegrateMRattleDrudeNoseHooverStepKernel : public ReferenceStepKernel {
public:
    using ReferenceStepKernel::ReferenceStepKernel;
    /** The Drude groups, and both chains at rest, declared to the state. */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;
    /** Both chains' energies. */
    double computeHeatBathEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override;
    double computeDrudeKineticEnergy(OpenMM::ContextImpl& context, int& numDrudeParticles) override;

private:
    /** Both chains over half a step, then the velocities scaled by their factors. */
    void chainsHalfStep(const RigidBodyIntegrator& integrator);
    DrudeGroups groups;
    RigidBodyThermostats::NoseHooverChain chain, drudeChain;
};

} // namespace MRattlePlugin

#endif
