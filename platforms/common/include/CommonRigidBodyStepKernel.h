#ifndef MRATTLE_COMMON_RIGID_BODY_STEP_KERNEL_H_
#define MRATTLE_COMMON_RIGID_BODY_STEP_KERNEL_H_

#include "CommonRigidBodyDynamics.h"
#include "RigidBodyIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/common/ContextSelector.h"
#include <string>
#include <vector>

namespace MRattlePlugin {

/**
 * Everything of a rigid-body step kernel on the common compute platforms but the step
 * itself, which a kernel supplies with execute() for its integrator class: the shared work
 * is CommonRigidBodyDynamics'.
 */
template <class IntegratorClass>
class CommonRigidBodyStepKernel : public RigidBodyStepKernel, public RigidBodyState {
public:
    typedef IntegratorClass Integrator;
    /** Failures are reported as the integrator's name (IntegratorNames). */
    CommonRigidBodyStepKernel(const std::string& name, const OpenMM::Platform& platform, OpenMM::ComputeContext& cc)
        : RigidBodyStepKernel(name, platform), dynamics(cc, IntegratorNames::ofStepKernel(name).integrator) {
    }
    RigidBodyState& getState() override {
        return *this;
    }
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override {
        execute(context, static_cast<const Integrator&>(integrator), forcesAreValid);
    }
    /** One step of this integrator class. */
    virtual void execute(OpenMM::ContextImpl& context, const Integrator& integrator, bool& forcesAreValid) = 0;
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override {
        OpenMM::ContextSelector selector(dynamics.computeContext());
        dynamics.initialize(system, topology);
        initializeIntegrator(system, static_cast<const Integrator&>(integrator));
    }
    void updateShapes(OpenMM::ContextImpl& context) override {
        OpenMM::ContextSelector selector(dynamics.computeContext());
        dynamics.updateShapes(context);
    }
    void projectVelocities(OpenMM::ContextImpl& context, double tolerance) override {
        OpenMM::ContextSelector selector(dynamics.computeContext());
        dynamics.projectVelocities(context, tolerance);
    }
    std::vector<OpenMM::Vec3> getVelocitiesForTemperature(OpenMM::ContextImpl& context, double temperature,
                                                          int randomSeed, double tolerance) override {
        OpenMM::ContextSelector selector(dynamics.computeContext());
        return dynamics.velocitiesForTemperature(context, temperature, randomSeed, tolerance);
    }
    double computeKineticEnergy(OpenMM::ContextImpl& context) override {
        OpenMM::ContextSelector selector(dynamics.computeContext());
        return dynamics.kineticEnergy();
    }
    void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational,
                                double& free) override {
        OpenMM::ContextSelector selector(dynamics.computeContext());
        dynamics.kineticEnergies(translational, rotational, free);
    }
    void finishSteps(OpenMM::ContextImpl& context) override {
        OpenMM::ContextSelector selector(dynamics.computeContext());
        dynamics.finishSteps();
    }
    bool isBodyLinear(int index) const override {
        return dynamics.isLinear(index);
    }
    int getBodyDegreesOfFreedom() const override {
        return dynamics.bodyDegreesOfFreedom();
    }
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override {
        dynamics.createCheckpoint(stream);
    }
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override {
        OpenMM::ContextSelector selector(dynamics.computeContext());
        dynamics.loadCheckpoint(stream);
    }
    void discardRefusedCheckpoint(OpenMM::ContextImpl& context) override {
    }
    IntegratorParameterValues getIntegratorParameters(OpenMM::ContextImpl& context) override {
        return {};
    }
    void setIntegratorParameters(OpenMM::ContextImpl& context, const IntegratorParameterValues& values) override {
    }

protected:
    /** What the integrator needs beyond the shared set-up (its own kernels, random numbers). */
    virtual void initializeIntegrator(const OpenMM::System& system, const Integrator& integrator) {
    }
    CommonRigidBodyDynamics dynamics;
};

} // namespace MRattlePlugin

#endif
