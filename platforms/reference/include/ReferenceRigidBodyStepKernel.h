#ifndef MRATTLE_REFERENCE_RIGID_BODY_STEP_KERNEL_H_
#define MRATTLE_REFERENCE_RIGID_BODY_STEP_KERNEL_H_

#include "ReferenceRigidBodyDynamics.h"
#include "RigidBodyIntegrator.h"
#include <vector>

namespace MRattlePlugin {

/**
 * Everything of a rigid-body step kernel on the Reference and CPU platforms but the step
 * itself, which a kernel supplies with its interface's execute() (e.g.
 * IntegrateMRattleStepKernel) as a list of the phases of ReferenceRigidBodyDynamics, the
 * shared work: the counterpart of CommonRigidBodyStepKernel.
 */
template <class StepKernel>
class ReferenceRigidBodyStepKernel : public StepKernel {
public:
    typedef typename StepKernel::IntegratorType Integrator;
    ReferenceRigidBodyStepKernel(const std::string& name, const OpenMM::Platform& platform)
        : StepKernel(name, platform), dynamics(StepKernel::IntegratorName()) {
    }
    std::string integratorName() const override {
        return StepKernel::IntegratorName();
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
