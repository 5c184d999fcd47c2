#ifndef MRATTLE_COMMON_RIGID_BODY_STEP_KERNEL_H_
#define MRATTLE_COMMON_RIGID_BODY_STEP_KERNEL_H_

#include "CommonRigidBodyDynamics.h"
#include "RigidBodyIntegrator.h"
#include "openmm/common/ContextSelector.h"
#include <string>
#include <vector>

namespace MRattlePlugin {

/**
 * Everything of a rigid-body step kernel on the common compute platforms but the step
 * itself, which a kernel supplies with its interface's execute() (e.g.
 * IntegrateMRattleStepKernel): the shared work is CommonRigidBodyDynamics'.
 */
template <class StepKernel>
class CommonRigidBodyStepKernel : public StepKernel {
public:
    typedef typename StepKernel::IntegratorType Integrator;
    /** Failures are reported as the interface's IntegratorName(). */
    CommonRigidBodyStepKernel(const std::string& name, const OpenMM::Platform& platform, OpenMM::ComputeContext& cc)
        : StepKernel(name, platform), dynamics(cc, StepKernel::IntegratorName()) {
    }
    std::string integratorName() const override {
        return StepKernel::IntegratorName();
    }
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

protected:
    /** What the integrator needs beyond the shared set-up (its own kernels, random numbers). */
    virtual void initializeIntegrator(const OpenMM::System& system, const Integrator& integrator) {
    }
    CommonRigidBodyDynamics dynamics;
};

} // namespace MRattlePlugin

#endif
