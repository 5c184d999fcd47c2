#ifndef MRATTLE_RIGID_BODY_KERNELS_H_
#define MRATTLE_RIGID_BODY_KERNELS_H_

#include "RigidBodyTopology.h"
#include "internal/RigidBodyState.h"
#include "openmm/KernelImpl.h"
#include "openmm/Platform.h"
#include "openmm/System.h"
#include <string>

namespace OpenMM {
class ContextImpl;
}

namespace MRattlePlugin {

class RigidBodyIntegrator;

/** An integrator's class name (what messages and a State's parameters call it) and its step kernel's name
    (checkpoints carry it). */
struct RigidBodyIntegratorName {
    const char* integrator;
    const char* stepKernel;
};

/** The plugin's integrators, each name typed here once; every platform's factory registers every entry of All. */
namespace IntegratorNames {
inline constexpr RigidBodyIntegratorName MRattle{"MRattleIntegrator", "IntegrateMRattleStep"};
inline constexpr RigidBodyIntegratorName MRattleLangevin{"MRattleLangevinIntegrator", "IntegrateMRattleLangevinStep"};
inline constexpr RigidBodyIntegratorName MRattleNoseHoover{"MRattleNoseHooverIntegrator",
                                                           "IntegrateMRattleNoseHooverStep"};
inline constexpr RigidBodyIntegratorName MRattleBussi{"MRattleBussiIntegrator", "IntegrateMRattleBussiStep"};
inline constexpr RigidBodyIntegratorName RigidSplitting{"RigidSplittingIntegrator", "IntegrateRigidSplittingStep"};
inline constexpr RigidBodyIntegratorName MRattleDrudeLangevin{"MRattleDrudeLangevinIntegrator",
                                                              "IntegrateMRattleDrudeLangevinStep"};
inline constexpr RigidBodyIntegratorName MRattleDrudeNoseHoover{"MRattleDrudeNoseHooverIntegrator",
                                                                "IntegrateMRattleDrudeNoseHooverStep"};
inline constexpr RigidBodyIntegratorName All[] = {MRattle,        MRattleLangevin,      MRattleNoseHoover,
                                                  MRattleBussi,   RigidSplitting,       MRattleDrudeLangevin,
                                                  MRattleDrudeNoseHoover};
/** The index in All of the integrator whose step kernel has this name; throws an OpenMMException if none has. */
OPENMM_EXPORT_MRATTLE int indexOfStepKernel(const std::string& stepKernelName);
/** The integrator whose step kernel has this name. */
inline const RigidBodyIntegratorName& ofStepKernel(const std::string& stepKernelName) {
    return All[indexOfStepKernel(stepKernelName)];
}
} // namespace IntegratorNames

/**
 * An integrator's step on a platform: made for one integrator class (its name in
 * IntegratorNames), with the platform's rigid-body state behind it.
 */
class OPENMM_EXPORT_MRATTLE RigidBodyStepKernel : public OpenMM::KernelImpl {
public:
    RigidBodyStepKernel(const std::string& name, const OpenMM::Platform& platform);
    ~RigidBodyStepKernel() override;
    /** @param topology  the bodies in effect; @param integrator  its settings now (e.g. a random seed) */
    virtual void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                            const RigidBodyIntegrator& integrator) = 0;
    /**
     * One step, a list of the state's phases (beginStep ... endStep). A step that fails throws
     * an OpenMMException naming the integrator, from this execute(), a later one of the same
     * step(n) call, or finishSteps() (the device platforms find a failure lazily), and leaves
     * positions, velocities, box, time and step count as they were before that step. The
     * platform kernel is made for one integrator class and casts `integrator` to it.
     *
     * forcesAreValid -- in: the Context's forces are those at the current positions for the
     * integration force groups; out: true after a step.
     */
    virtual void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) = 0;
    /** A thermostat's heat-bath energy; 0 for integrators without one. */
    virtual double computeHeatBathEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) {
        return 0;
    }
    /**
     * The Drude groups' relative kinetic energy KE_C (their Drude particles' motion relative
     * to their cores) now, and the number of Drude particles; 0 and 0 without Drude groups.
     */
    virtual double computeDrudeKineticEnergy(OpenMM::ContextImpl& context, int& numDrudeParticles) {
        numDrudeParticles = 0;
        return 0;
    }
    /** The platform's rigid-body state, which the API asks for everything but the step. */
    virtual RigidBodyState& getState() = 0;
};

} // namespace MRattlePlugin

#endif
