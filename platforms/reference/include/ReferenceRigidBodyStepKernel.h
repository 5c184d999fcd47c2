#ifndef MRATTLE_REFERENCE_RIGID_BODY_STEP_KERNEL_H_
#define MRATTLE_REFERENCE_RIGID_BODY_STEP_KERNEL_H_

#include "BodyShapeConstraints.h"
#include "HostRigidBodyRules.h"
#include "ReferenceRigidBodyDynamics.h"
#include "RigidBodyIntegrator.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/AndersenThermostat.h"
#include "openmm/kernels.h"
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
        try {
            integratePositions(context, integrator);  // leaves the Context as it was if it throws
        } catch (const OpenMM::OpenMMException& e) {
            throw OpenMM::OpenMMException(std::string(integratorName()) + ": " + e.what());
        }
        forcesAreValid = false;
        // integratePositions left the state before it in the step buffers: a failure from
        // here on puts it back, so a step that returns has produced a finite, valid state.
        try {
            context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
            finishStep(context, integrator);
            requireFiniteStepResult(context);
        } catch (const OpenMM::OpenMMException& e) {
            ReferenceRigidBodyDynamics::positions(context).swap(newPositions);
            ReferenceRigidBodyDynamics::velocities(context).swap(newVelocities);
            throw OpenMM::OpenMMException(std::string(integratorName()) + ": " + e.what() +
                                          "; the step was not taken (positions and velocities are as before it)");
        }
        ReferenceRigidBodyDynamics::advanceClock(context, integrator.getStepSize());
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
        try {
            dynamics->projectNonRigidVelocities(ReferenceRigidBodyDynamics::positions(context), velocities, tolerance);
            requireFinite(velocities, "velocity projected at the current positions (a degenerate constraint?)");
        } catch (...) {
            velocities = given;  // a refused projection (not finite, or constraints not converged) changes nothing
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
    void discardRefusedCheckpoint(OpenMM::ContextImpl& context) override {
        // OpenMM's Reference and CPU platforms keep one process-wide random generator (the
        // AndersenThermostat's, among others) whose state a checkpoint overwrites unchecked,
        // garbage included. Initialising OpenMM's thermostat kernel reseeds it (with the
        // System's thermostat seed if it has one), so it rebuilds a valid state.
        OpenMM::AndersenThermostat seeded(0, 0);
        const OpenMM::System& system = context.getSystem();
        for (int f = 0; f < system.getNumForces(); f++)
            if (const auto* thermostat = dynamic_cast<const OpenMM::AndersenThermostat*>(&system.getForce(f)))
                seeded.setRandomNumberSeed(thermostat->getRandomNumberSeed());
        OpenMM::Kernel reseed = context.getPlatform().createKernel(OpenMM::ApplyAndersenThermostatKernel::Name(), context);
        reseed.getAs<OpenMM::ApplyAndersenThermostatKernel>().initialize(system, seeded);
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
     * projection (a leapfrog integrator has nothing to do). May throw an OpenMMException;
     * the step is then undone.
     */
    virtual void finishStep(OpenMM::ContextImpl& context, const Integrator& integrator) {
        dynamics->kickAndProject(context, integrator.getStepSize(), integrator.getConstraintTolerance());
    }
    /**
     * The first half of the step: half kick, drift, the integrator's position update,
     * free-particle constraints, virtual sites. Throws an OpenMMException, with the Context
     * unchanged, if the update fails. On success the Context's position and velocity arrays
     * are the new ones and newPositions, newVelocities hold those from before (swapped),
     * so that execute() can undo the step.
     */
    virtual void integratePositions(OpenMM::ContextImpl& context, const Integrator& integrator) = 0;
    /** The integrator's class name, for messages. */
    virtual const char* integratorName() const = 0;
    /**
     * Throw naming the first massive particle whose new position, velocity or force (at the
     * new positions: the next step's kick) is not finite.
     */
    void requireFiniteStepResult(OpenMM::ContextImpl& context) const {
        const std::vector<OpenMM::Vec3>& x = ReferenceRigidBodyDynamics::positions(context);
        const std::vector<OpenMM::Vec3>& v = ReferenceRigidBodyDynamics::velocities(context);
        const std::vector<OpenMM::Vec3>& f = ReferenceRigidBodyDynamics::forces(context);
        const std::vector<double>& inverseMass = dynamics->inverseMasses();
        for (size_t i = 0; i < x.size(); i++) {
            if (inverseMass[i] == 0)
                continue;  // massless: never integrated, finite since set
            const char* what = !std::isfinite(x[i][0] + x[i][1] + x[i][2])   ? "position"
                               : !std::isfinite(f[i][0] + f[i][1] + f[i][2]) ? "force at the new positions"
                               : !std::isfinite(v[i][0] + v[i][1] + v[i][2]) ? "velocity"
                                                                             : nullptr;
            if (what != nullptr)
                throw OpenMM::OpenMMException(std::string("the ") + what + " of particle " + std::to_string(i) +
                                              " is not finite");
        }
    }

    std::unique_ptr<ReferenceRigidBodyDynamics> dynamics;
    std::unique_ptr<BodyShapeConstraints> shapes;
    std::vector<OpenMM::Vec3> newPositions, newVelocities;  // step buffers
};

} // namespace MRattlePlugin

#endif
