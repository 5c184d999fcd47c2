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

class MRattleIntegrator;
class RigidSplittingIntegrator;

/**
 * Operations every rigid-body integrator needs from its platform: velocity projection
 * onto rigid-body motion (with free-particle constraints) and the kinetic energy.
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
};

/**
 * One M-RATTLE step, split around the force evaluation at the new positions.
 */
class OPENMM_EXPORT_MRATTLE IntegrateMRattleStepKernel : public RigidBodyKernel {
public:
    static std::string Name() {
        return "IntegrateMRattleStep";
    }
    IntegrateMRattleStepKernel(const std::string& name, const OpenMM::Platform& platform) : RigidBodyKernel(name, platform) {
    }
    ~IntegrateMRattleStepKernel() override;
    /** Half kick, drift, position reset (bodies by M-RATTLE, free constraints by RATTLE), virtual sites. */
    virtual void integratePositions(OpenMM::ContextImpl& context, const MRattleIntegrator& integrator) = 0;
    /** Half kick with the new forces, velocity reset; advances time and step count. */
    virtual void integrateVelocities(OpenMM::ContextImpl& context, const MRattleIntegrator& integrator) = 0;
};

/**
 * One step of the symplectic splitting baseline (RigidSplittingIntegrator), split around
 * the force evaluation at the new positions.
 */
class OPENMM_EXPORT_MRATTLE IntegrateRigidSplittingStepKernel : public RigidBodyKernel {
public:
    static std::string Name() {
        return "IntegrateRigidSplittingStep";
    }
    IntegrateRigidSplittingStepKernel(const std::string& name, const OpenMM::Platform& platform)
        : RigidBodyKernel(name, platform) {
    }
    ~IntegrateRigidSplittingStepKernel() override;
    /** Half kick, drift and free rotor of every body; velocity Verlet and RATTLE for free particles; virtual sites. */
    virtual void integratePositions(OpenMM::ContextImpl& context, const RigidSplittingIntegrator& integrator) = 0;
    /** Half kick with the new forces, velocity reset; advances time and step count. */
    virtual void integrateVelocities(OpenMM::ContextImpl& context, const RigidSplittingIntegrator& integrator) = 0;
};

} // namespace MRattlePlugin

#endif
