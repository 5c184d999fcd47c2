#ifndef MRATTLE_REFERENCE_RIGID_BODY_STEP_KERNEL_H_
#define MRATTLE_REFERENCE_RIGID_BODY_STEP_KERNEL_H_

#include "ReferenceRigidBodyDynamics.h"
#include "RigidBodyIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include <vector>

namespace MRattlePlugin {

/**
 * Everything of a rigid-body step kernel on the Reference and CPU platforms but the step
 * itself, which a kernel supplies with execute() for its integrator class as a list of the
 * phases of ReferenceRigidBodyDynamics, the shared work.
 */
template <class IntegratorClass>
class ReferenceRigidBodyStepKernel : public RigidBodyStepKernel, public RigidBodyState {
public:
    typedef IntegratorClass Integrator;
    ReferenceRigidBodyStepKernel(const std::string& name, const OpenMM::Platform& platform)
        : RigidBodyStepKernel(name, platform), dynamics(IntegratorNames::ofStepKernel(name).integrator) {
    }
    RigidBodyState& getState() override {
        return *this;
    }
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override {
        execute(context, static_cast<const Integrator&>(integrator), forcesAreValid);
    }
    /** One step of this integrator class. */
    virtual void execute(OpenMM::ContextImpl& context, const Integrator& integrator, bool& forcesAreValid) = 0;
    void finishSteps(OpenMM::ContextImpl& context) override {
    }
    IntegratorParameterValues getIntegratorParameters(OpenMM::ContextImpl& context) override {
        return {};
    }
    void setIntegratorParameters(OpenMM::ContextImpl& context, const IntegratorParameterValues& values) override {
    }
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override {
        dynamics.initialize(system, topology);
        initializeIntegrator(system, static_cast<const Integrator&>(integrator));
    }
    void updateShapes(OpenMM::ContextImpl& context) override {
        dynamics.updateShapes(context);
    }
    void projectVelocities(OpenMM::ContextImpl& context, double tolerance) override {
        dynamics.projectVelocities(context, tolerance);
    }
    std::vector<OpenMM::Vec3> getVelocitiesForTemperature(OpenMM::ContextImpl& context, double temperature,
                                                          int randomSeed, double tolerance) override {
        return dynamics.velocitiesForTemperature(context, temperature, randomSeed, tolerance);
    }
    double computeKineticEnergy(OpenMM::ContextImpl& context) override {
        return dynamics.kineticEnergy(context);
    }
    void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational,
                                double& free) override {
        dynamics.kineticEnergies(context, translational, rotational, free);
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
        dynamics.loadCheckpoint(stream);
    }
    void discardRefusedCheckpoint(OpenMM::ContextImpl& context) override {
        dynamics.discardRefusedCheckpoint(context);
    }

protected:
    /** What the integrator needs beyond the shared set-up (e.g. its random stream's seed). */
    virtual void initializeIntegrator(const OpenMM::System& system, const Integrator& integrator) {
    }
    ReferenceRigidBodyDynamics dynamics;
};

} // namespace MRattlePlugin

#endif
