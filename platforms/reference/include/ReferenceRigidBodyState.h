#ifndef MRATTLE_REFERENCE_RIGID_BODY_STATE_H_
#define MRATTLE_REFERENCE_RIGID_BODY_STATE_H_

#include "RigidBodyTopology.h"
#include "internal/BodyShapeConstraints.h"
#include "internal/DrudeGroups.h"
#include "internal/RigidBodyState.h"
#include "mrattle/RigidBodyMath.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include "openmm/internal/ThreadPool.h"
#include "openmm/reference/ReferenceConstraints.h"
#include <functional>
#include <iosfwd>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace MRattlePlugin {

class RigidBodyIntegrator;

/**
 * The rigid-body state of a Context on the Reference and CPU platforms: the bodies, their
 * shapes, the free constraints, the random stream, the integrator's own variables, and the
 * phases a step kernel's execute() lists (beginStep ... endStep) on the Context's host
 * arrays, over the numerical core, on the CPU platform's threads. A phase that fails puts
 * back everything from the step's start (atoms, declared variables) and throws naming the
 * integrator. ReferenceRigidBodyState.cpp: phases, rollback, checkpoints, the API's
 * queries; ReferenceRigidBodyArithmetic.cpp: the per-body and per-particle work.
 */
class ReferenceRigidBodyState : public RigidBodyState {
public:
    /** @param stepKernelName  the kernel's name, which names the integrator failures are reported as */
    explicit ReferenceRigidBodyState(const std::string& stepKernelName);
    ReferenceRigidBodyState(const ReferenceRigidBodyState&) = delete;   // views point into bodies
    ReferenceRigidBodyState& operator=(const ReferenceRigidBodyState&) = delete;
    /** Take the bodies, free constraints and Andersen thermostat of the System. */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology);

    /**
     * The integrator's own variables (a thermostat's), declared once at initialize: each
     * step's start backs them up and a failed step puts them back; checkpoints hold them
     * (before the random stream; their common length first if lengthFirst, as a Nose-Hoover
     * chain's); they are the integrator parameters a State carries. withRandomStream: the
     * random stream is put back with them (CSVR draws from it).
     */
    typedef std::vector<std::pair<std::string, std::vector<double>*> > Variables;
    void declareIntegratorState(const Variables& variables, bool lengthFirst, bool withRandomStream);
    /** Seed the random stream, unless an AndersenThermostat's seed or a checkpoint set it (0: a new seed). */
    void seedRandom(int seed);
    /** The random stream (Andersen body collisions, Langevin noise, CSVR's draws). */
    std::mt19937_64& randomStream() {
        return random;
    }
    /** The System's degrees of freedom at the last positions set, by RigidBodyTopology's rule. */
    int getNumDegreesOfFreedom() const;

    // ---- The phases of a step --------------------------------------------------------
    /** CPU threads (first step), Andersen collisions of whole bodies, forces unless valid, then the step's backup. */
    void beginStep(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid);
    /** A kick of the velocities over this time with the Context's forces. */
    void kick(double time);
    /** A kick over kickTime (0: none) in the same pass, a drift over h, each body's reset, the free constraints. */
    void driftAndReset(double kickTime, double h, double tolerance);
    /** RATTLE's velocity step: free constraints, then every body's rigid-body projection. */
    void project(double tolerance);
    /** Virtual sites at the new positions, then the forces there. */
    void computeForces(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid);
    /** Every velocity times this factor (a thermostat's). */
    void scaleVelocities(double factor);
    /** Ornstein-Uhlenbeck over time h on every massive particle's velocity (Langevin's noise, then project()). */
    void addNoise(double friction, double temperature, double h);
    /**
     * The Drude integrators' noise over time h (then project()): each group's rigid part
     * (DrudeGroups) at the friction and temperature, its Drude particles' relative motion at
     * the Drude friction and temperature, every other massive particle as addNoise().
     */
    void addDrudeNoise(const DrudeGroups& groups, double friction, double temperature, double drudeFriction,
                       double drudeTemperature, double h);
    /**
     * The hard wall after the drift over h: a Drude particle farther than maxDistance from its
     * core bounces back (OpenMM's DrudeLangevin; a core in a body stays, the Drude particle
     * alone moves); one beyond twice maxDistance fails the step.
     */
    void bounceDrudes(const DrudeGroups& groups, double maxDistance, double drudeTemperature, double h);
    /**
     * The step's kinetic energy split by the Drude groups: relative = KE_C (the Drude
     * particles' motion relative to their cores), rigid = KE - KE_C (the groups' rigid
     * motion and every other particle), in kJ/mol.
     */
    void computeDrudeKineticEnergies(const DrudeGroups& groups, double& rigid, double& relative);
    /**
     * A two-chain thermostat's scaling: each group's rigid part v_R of the velocities times
     * factor and its relative part v - v_R times drudeFactor; every other velocity times
     * factor. Both parts lie in the constrained space: nothing to project afterwards. Both
     * factors 1 leave the velocities untouched.
     */
    void scaleDrudeVelocities(const DrudeGroups& groups, double factor, double drudeFactor);
    /** The splitting baseline's position step: free particles kick and drift, each body's free-rotor splitting. */
    void rotorDriftAndReset(double h, double tolerance);
    /** A non-finite position, velocity or force fails the step; else the clock advances. */
    void endStep(double stepSize, bool& forcesAreValid);

    // ---- RigidBodyState ----------------------------------------------------------------
    void updateShapes(OpenMM::ContextImpl& context) override;
    void projectVelocities(OpenMM::ContextImpl& context, double tolerance) override;
    std::vector<OpenMM::Vec3> getVelocitiesForTemperature(OpenMM::ContextImpl& context, double temperature,
                                                          int randomSeed, double tolerance) override;
    double computeKineticEnergy(OpenMM::ContextImpl& context) override;
    void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational,
                                double& free) override;
    /** Each step was checked as it ended: nothing to do. */
    void finishSteps(OpenMM::ContextImpl& context) override {
    }
    bool isBodyLinear(int index) const override {
        return shapes[index] == RigidBodyMath::Shape::Linear;
    }
    int getBodyDegreesOfFreedom() const override;
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override;
    void discardRefusedCheckpoint(OpenMM::ContextImpl& context) override;
    IntegratorParameterValues getIntegratorParameters(OpenMM::ContextImpl& context) override;
    void setIntegratorParameters(OpenMM::ContextImpl& context, const IntegratorParameterValues& values) override;

private:
    // ---- Failure and rollback (ReferenceRigidBodyState.cpp) ------------------------------
    /** Run a phase: an OpenMMException from it fails the step. */
    void phase(const std::function<void()>& work);
    /** Put back everything from the step's start and throw what failed, naming the integrator. */
    [[noreturn]] void failStep(const std::string& what);
    /** Throw naming the first massive particle whose position, velocity or force is not finite. */
    void requireFiniteStepResult();
    std::vector<OpenMM::Vec3>& positions();
    std::vector<OpenMM::Vec3>& velocities();
    const std::vector<OpenMM::Vec3>& forces();
    /** The step buffers become the Context's positions and velocities. */
    void acceptNewState();

    // ---- Arithmetic on arrays (ReferenceRigidBodyArithmetic.cpp) --------------------------
    /** Use this many threads for per-body and per-particle work (results do not depend on it). */
    void setThreads(int numThreads);
    /** work(body) for every body; the smallest body for which it returned false (INT_MAX if none). */
    int forEachBody(const std::function<bool(int)>& work);
    /** work(begin, end) on contiguous particle ranges, one per thread when there are enough particles. */
    void forEachParticleRange(const std::function<void(int, int)>& work);
    /**
     * work(begin, end) on ranges of bodies (returning the first failed body, INT_MAX if none)
     * and freeWork(begin, end), if given, on ranges of the free particles, in one parallel
     * region; the smallest failed body.
     */
    int forEachBodyRangeAndFreeParticle(const std::function<int(int, int)>& work,
                                        const std::function<void(int, int)>& freeWork);
    /** work(t) for t = 0 .. numThreads - 1, the last on the calling thread. */
    void forEachThread(const std::function<void(int)>& work);
    /** The core's kick by these forces (none if null) over this time. */
    RigidBodyMath::Kick kickOf(const std::vector<OpenMM::Vec3>* forces, double time) const;
    /** RATTLE's position step of the free constraints; throws naming one that did not converge. */
    void constrainFreePositions(std::vector<OpenMM::Vec3>& oldPositions, std::vector<OpenMM::Vec3>& newPositions,
                                double tolerance);
    /** RATTLE's velocity step of the free constraints; throws naming one that did not converge. */
    void constrainFreeVelocities(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                                 double tolerance);
    /** Free constraints, then every body's projection onto rigid-body motion. */
    void projectArrays(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities, double tolerance);
    /** The same, but bodies whose velocities are already rigid keep them bit for bit. */
    void projectNonRigidArrays(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                               double tolerance);
    /** Sum of m v^2 / 2 over the massive particles. */
    double kineticEnergyOf(const std::vector<OpenMM::Vec3>& velocities) const;
    /** Every body with a collided atom gets fresh thermal velocities for all its atoms, then all are made rigid. */
    void collideBodies(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                       double temperature, double tolerance);

    const std::string integratorName;
    RigidBodyTopology bodies;
    std::vector<RigidBodyMath::BodyView> views;   // one per body, its linear flag from shapes
    std::vector<RigidBodyMath::Shape> shapes;
    std::unique_ptr<BodyShapeConstraints> shapeConstraints;
    std::vector<double> inverseMass;
    std::vector<double> mass;   // 1 / inverseMass (0 for massless particles), for the Drude groups
    std::vector<OpenMM::Vec3> drudeNoise, drudeRigid;   // addDrudeNoise's scratch
    std::vector<int> otherParticles;   // neither body members nor free: massless (virtual sites too)
    std::unique_ptr<OpenMM::ReferenceConstraints> freeConstraints;
    std::vector<std::pair<int, int> > freeConstraintAtoms;   // the free constraints, to check what they left
    std::vector<double> freeConstraintDistances;
    bool andersen = false, hasVirtualSites = false, threadsChecked = false;
    bool forcesComputed = false;  // the step under way has had its computeForces phase
    int numThreads = 1;
    std::unique_ptr<OpenMM::ThreadPool> helpers;   // numThreads - 1 workers; the caller is the last
    std::mt19937_64 random;
    bool randomIsSet = false;
    // The integrator's declared variables and what a step's start backs up.
    Variables variables;
    bool lengthInCheckpoint = false, randomInStep = false;
    std::vector<std::vector<double> > startVariables;
    std::mt19937_64 startRandom;
    OpenMM::ContextImpl* stepContext = nullptr;   // the Context of the step under way
    std::vector<OpenMM::Vec3> startPositions, startVelocities;   // the state at the step's start
    std::vector<OpenMM::Vec3> nextPositions, nextVelocities;     // step buffers
};

} // namespace MRattlePlugin

#endif
