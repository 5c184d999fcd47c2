#ifndef MRATTLE_REFERENCE_RIGID_BODY_STEP_KERNEL_H_
#define MRATTLE_REFERENCE_RIGID_BODY_STEP_KERNEL_H_

#include "BodyShapeConstraints.h"
#include "HostRigidBodyRules.h"
#include "ReferenceRigidBodyDynamics.h"
#include "RigidBodyIntegrator.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace MRattlePlugin {

/**
 * Everything of a rigid-body step kernel on the Reference and CPU platforms but the
 * integrator's position update: set-up, the step, velocity projection, temperatures,
 * kinetic energy, shapes and checkpoints. A kernel derives from it with its interface
 * (e.g. IntegrateMRattleStepKernel) and supplies integratePositions().
 */
template <class StepKernel>
class ReferenceRigidBodyStepKernel : public StepKernel {
public:
    typedef typename StepKernel::IntegratorType Integrator;
    ReferenceRigidBodyStepKernel(const std::string& name, const OpenMM::Platform& platform) : StepKernel(name, platform) {
    }
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override {
        dynamics.reset(new ReferenceRigidBodyDynamics(system, topology));
        shapes.reset(new BodyShapeConstraints(system, topology));
        newPositions.resize(system.getNumParticles());
        newVelocities.resize(system.getNumParticles());
        hasVirtualSites = false;
        for (int i = 0; i < system.getNumParticles(); i++)
            hasVirtualSites |= system.isVirtualSite(i);
    }
    void execute(OpenMM::ContextImpl& context, const Integrator& integrator, bool& forcesAreValid) override {
        useThreadsOf(context);
        const double tolerance = integrator.getConstraintTolerance();
        if (dynamics->hasAndersenThermostat())
            dynamics->collideBodies(context, tolerance);
        if (!forcesAreValid)
            context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
        integratePositions(context, integrator);  // leaves the Context as it was if it throws
        forcesAreValid = false;
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
        finishStep(context, integrator);
        forcesAreValid = true;
    }
    void updateShapes(OpenMM::ContextImpl& context) override {
        std::vector<OpenMM::Vec3>& positions = ReferenceRigidBodyDynamics::positions(context);
        requireFinite(positions, "position");
        if (shapes->apply(positions))
            context.computeVirtualSites();
        dynamics->updateShapes(positions);
    }
    void projectVelocities(OpenMM::ContextImpl& context, double tolerance) override {
        std::vector<OpenMM::Vec3>& velocities = ReferenceRigidBodyDynamics::velocities(context);
        requireFinite(velocities, "velocity");
        const std::vector<OpenMM::Vec3> given = velocities;  // only when velocities are set, not in the step
        dynamics->projectNonRigidVelocities(ReferenceRigidBodyDynamics::positions(context), velocities, tolerance);
        try {
            requireFinite(velocities, "velocity projected at the current positions (a degenerate constraint?)");
        } catch (...) {
            velocities = given;
            throw;
        }
    }
    std::vector<OpenMM::Vec3> getVelocitiesForTemperature(OpenMM::ContextImpl& context, double temperature,
                                                          int randomSeed, double tolerance) override {
        return dynamics->velocitiesForTemperature(ReferenceRigidBodyDynamics::positions(context), temperature,
                                                  randomSeed, tolerance);
    }
    double computeKineticEnergy(OpenMM::ContextImpl& context) override {
        return dynamics->kineticEnergy(ReferenceRigidBodyDynamics::velocities(context));
    }
    void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational,
                                double& free) override {
        dynamics->kineticEnergies(ReferenceRigidBodyDynamics::velocities(context), translational, rotational, free);
    }
    bool isBodyLinear(int index) const override {
        return dynamics->isLinear(index);
    }
    int getBodyDegreesOfFreedom() const override {
        return dynamics->getBodyDegreesOfFreedom();
    }
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override {
        dynamics->writeState(stream);
    }
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override {
        dynamics->readState(stream);
    }

protected:
    /**
     * On the CPU platform, the per-body work uses its Threads; read at the first step (the
     * platform's properties cannot be asked for while the Context is being made).
     */
    void useThreadsOf(OpenMM::ContextImpl& context) {
        if (threadsChecked)
            return;
        threadsChecked = true;
        if (context.getPlatform().getName() == "CPU")
            dynamics->setThreads(std::stoi(context.getPlatform().getPropertyValue(context.getOwner(), "Threads")));
    }
    bool threadsChecked = false;
    /**
     * Place the virtual sites at the new positions (OpenMM 7.7 and 8.x alike). OpenMM's
     * Reference code loops over every particle to find them: skipped when there are none.
     */
    void placeVirtualSites(OpenMM::ContextImpl& context) {
        if (hasVirtualSites)
            context.computeVirtualSites();
    }
    bool hasVirtualSites = false;
    static void requireFinite(const std::vector<OpenMM::Vec3>& values, const char* what) {
        HostRigidBodyRules::requireFinite(values, what);
    }
    /**
     * After the forces at the new positions: velocity Verlet's closing half kick and the
     * projection (a leapfrog integrator only advances the clock); advances time and step count.
     */
    virtual void finishStep(OpenMM::ContextImpl& context, const Integrator& integrator) {
        dynamics->kickAndProject(context, integrator.getStepSize(), integrator.getConstraintTolerance());
    }
    /**
     * The first half of the step: half kick, drift, the integrator's position update,
     * free-particle constraints, virtual sites. Throws an OpenMMException, with the Context
     * unchanged, if the update fails.
     */
    virtual void integratePositions(OpenMM::ContextImpl& context, const Integrator& integrator) = 0;

    std::unique_ptr<ReferenceRigidBodyDynamics> dynamics;
    std::unique_ptr<BodyShapeConstraints> shapes;
    std::vector<OpenMM::Vec3> newPositions, newVelocities;  // step buffers
};

} // namespace MRattlePlugin

#endif
