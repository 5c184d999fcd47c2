#ifndef MRATTLE_RIGID_BODY_KERNELS_H_
#define MRATTLE_RIGID_BODY_KERNELS_H_

#include "RigidBodySet.h"
#include "openmm/KernelImpl.h"
#include "openmm/Platform.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include <string>
#include <vector>

namespace OpenMM {
class ContextImpl;
}

namespace MRattlePlugin {

class RigidBodyIntegrator;

/**
 * What every rigid-body integrator needs from its platform: one step in two halves around
 * the force evaluation at the new positions, velocity projection onto rigid-body motion
 * (with free-particle constraints) and the kinetic energy. Each integrator has its own
 * kernel name (a subclass below) so a platform can implement each one.
 */
class OPENMM_EXPORT_MRATTLE RigidBodyKernel : public OpenMM::KernelImpl {
public:
    RigidBodyKernel(const std::string& name, const OpenMM::Platform& platform) : OpenMM::KernelImpl(name, platform) {
    }
    ~RigidBodyKernel() override;
    /**
     * @param bodies  the integrator's body bookkeeping; it outlives the kernel
     */
    virtual void initialize(const OpenMM::System& system, const RigidBodySet& bodies) = 0;
    /**
     * Replace velocities (one per particle) by their projection onto rigid-body motion at
     * the Context's positions; velocities along free-particle constraints are removed to
     * the given tolerance.
     */
    virtual void projectVelocities(OpenMM::ContextImpl& context, std::vector<OpenMM::Vec3>& velocities, double tolerance) = 0;
    /** The same, in place, on the velocities held by the Context. */
    virtual void projectContextVelocities(OpenMM::ContextImpl& context, double tolerance) = 0;
    /** Sum of m v^2 / 2 over the Context's velocities. */
    virtual double computeKineticEnergy(OpenMM::ContextImpl& context) = 0;
    /** First half: half kick, drift and the integrator's position update, free-particle constraints, virtual sites. */
    virtual void integratePositions(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) = 0;
    /** Second half, with the forces at the new positions: half kick, velocity reset; advances time and step count. */
    virtual void integrateVelocities(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) = 0;
};

/** M-RATTLE: the position update resets each body with the 3 + 3 conditions. */
class OPENMM_EXPORT_MRATTLE IntegrateMRattleStepKernel : public RigidBodyKernel {
public:
    static std::string Name() {
        return "IntegrateMRattleStep";
    }
    IntegrateMRattleStepKernel(const std::string& name, const OpenMM::Platform& platform) : RigidBodyKernel(name, platform) {
    }
    ~IntegrateMRattleStepKernel() override;
};

/** The symplectic splitting baseline: the position update is a free-rotor splitting per body. */
class OPENMM_EXPORT_MRATTLE IntegrateRigidSplittingStepKernel : public RigidBodyKernel {
public:
    static std::string Name() {
        return "IntegrateRigidSplittingStep";
    }
    IntegrateRigidSplittingStepKernel(const std::string& name, const OpenMM::Platform& platform)
        : RigidBodyKernel(name, platform) {
    }
    ~IntegrateRigidSplittingStepKernel() override;
};

} // namespace MRattlePlugin

#endif
