#ifndef MRATTLE_REFERENCE_RIGID_BODY_OPERATIONS_H_
#define MRATTLE_REFERENCE_RIGID_BODY_OPERATIONS_H_

#include "RigidBodyTopology.h"
#include "mrattle/RigidBodyMath.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include "openmm/internal/ThreadPool.h"
#include "openmm/reference/ReferenceConstraints.h"
#include <climits>
#include <functional>
#include <iosfwd>
#include <memory>
#include <random>
#include <vector>

namespace MRattlePlugin {

/**
 * The rigid-body work on host arrays of positions and velocities that the phases of a step
 * (ReferenceRigidBodyDynamics) are made of, on the Reference and CPU platforms: the
 * kernel's copy of the body topology and its per-configuration state (which bodies are
 * linear), RATTLE for constraints among free particles
 * (OpenMM's own ReferenceConstraints), velocity projection, kinetic energy, temperature
 * velocities and the Andersen body collisions with their random stream, on the CPU
 * platform's threads.
 */
class ReferenceRigidBodyOperations {
public:
    ReferenceRigidBodyOperations(const OpenMM::System& system, const RigidBodyTopology& topology);

    const RigidBodyTopology& topology() const {
        return bodies;
    }
    const std::vector<double>& inverseMasses() const {
        return inverseMass;
    }
    ReferenceRigidBodyOperations(const ReferenceRigidBodyOperations&) = delete;  // views point into bodies
    ReferenceRigidBodyOperations& operator=(const ReferenceRigidBodyOperations&) = delete;
    /** The numerical core's view of one body. */
    const RigidBodyMath::BodyView& view(int body) const {
        return views[body];
    }
    /**
     * Use this many threads for the per-body work (the CPU platform's Threads). Each body is
     * computed the same way whichever thread takes it, so results do not depend on it.
     */
    void setThreads(int numThreads);
    /**
     * Call work(body) for every body, on the threads when there are enough bodies to pay for
     * them. work returns false for a body that failed; the smallest such index is returned
     * (INT_MAX if none), so which body is reported does not depend on the threads either.
     */
    int forEachBody(const std::function<bool(int)>& work);
    /**
     * Call work(begin, end) on contiguous ranges covering every particle, one per thread
     * when there are enough particles to pay for them: for per-atom loops (kicks, drifts)
     * whose atoms are independent, so results do not depend on the threads.
     */
    void forEachParticleRange(const std::function<void(int, int)>& work);

    /** Classify each body's shape (linear or not) from the given positions. */
    void updateShapes(const std::vector<OpenMM::Vec3>& positions);
    bool isLinear(int body) const {
        return shapes[body] == RigidBodyMath::Shape::Linear;
    }
    /** 6 per body, 5 if linear, 3 if its atoms coincide. */
    int getBodyDegreesOfFreedom() const;

    /**
     * Drift over time h from positions x with velocities v, then RATTLE for the free
     * constraints and M-RATTLE's reset of every body: writes every particle's new position
     * and velocity (formed from the displacement) into newPositions and newVelocities. Throws
     * an OpenMMException if a body finds no rotation or a result is not finite; x and v are
     * not changed. With forces, each massive particle's velocity first gets the kick
     * f (kickTime / m), in the same pass (velocity Verlet's first half kick).
     */
    void driftAndReset(std::vector<OpenMM::Vec3>& x, const std::vector<OpenMM::Vec3>& v, double h, double tolerance,
                       std::vector<OpenMM::Vec3>& newPositions, std::vector<OpenMM::Vec3>& newVelocities,
                       const std::vector<OpenMM::Vec3>* forces = nullptr, double kickTime = 0);
    /**
     * RATTLE position step for free-particle constraints: moves newPositions onto the
     * constraints. Throws an OpenMMException naming a constraint that did not converge
     * (OpenMM's solver gives up silently); oldPositions are not changed.
     */
    void constrainFreePositions(std::vector<OpenMM::Vec3>& oldPositions, std::vector<OpenMM::Vec3>& newPositions,
                                double tolerance);
    /** RATTLE velocity step for free-particle constraints; throws if it did not converge. */
    void constrainFreeVelocities(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                                 double tolerance);
    /** Free constraints, then every body's rigid-body projection (RATTLE's velocity step). */
    void projectVelocities(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities, double tolerance);
    /** The same, but bodies whose velocities are already rigid keep them bit for bit. */
    void projectNonRigidVelocities(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                                   double tolerance);
    double kineticEnergy(const std::vector<OpenMM::Vec3>& velocities) const;
    /** kineticEnergy() split into the bodies' translation and rotation and the free particles (RigidBodyState). */
    void kineticEnergies(const std::vector<OpenMM::Vec3>& velocities, double& translational, double& rotational,
                         double& free) const;
    /** A kick v += f (time / m) of every massive particle. */
    void kick(std::vector<OpenMM::Vec3>& velocities, const std::vector<OpenMM::Vec3>& forces, double time);
    /** Rigid-body Maxwell-Boltzmann velocities at exactly this temperature (RigidBodyState). */
    std::vector<OpenMM::Vec3> velocitiesForTemperature(std::vector<OpenMM::Vec3>& positions, double temperature,
                                                       int randomSeed, double tolerance);

    /** True if the System has an AndersenThermostat, whose collisions must act on whole bodies. */
    bool hasAndersenThermostat() const {
        return andersen;
    }
    /**
     * After the thermostat has randomised single atoms: every body with a collided atom
     * (its velocities are no longer rigid) gets fresh Maxwell-Boltzmann velocities for all
     * its atoms from this kernel's random stream, then every velocity is made rigid.
     */
    void collideBodies(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities, double temperature,
                       double tolerance);
    /**
     * The kernel's random stream (Andersen body collisions, Langevin noise). It is seeded from
     * an AndersenThermostat's seed when the System has one; otherwise seedRandom() seeds it
     * unless a checkpoint has already restored it.
     */
    std::mt19937_64& random() {
        return collisionRandom;
    }
    void seedRandom(int seed);
    /**
     * The random stream, for checkpoints: written unframed (the checkpoint header frames the
     * kernel's state), so an integrator's kernel may write state of its own after it and read
     * it back after readState(). readState() also reads the state of a format-3 checkpoint.
     */
    void writeState(std::ostream& stream) const;
    void readState(std::istream& stream);

private:
    RigidBodyTopology bodies;
    std::vector<double> inverseMass;
    std::vector<RigidBodyMath::Shape> shapes;
    std::vector<int> otherParticles;   // neither body members nor free: massless (virtual sites too)
    std::unique_ptr<OpenMM::ReferenceConstraints> freeConstraints;
    std::vector<std::pair<int, int> > freeConstraintAtoms;   // the free constraints, to check what they left
    std::vector<double> freeConstraintDistances;
    bool andersen = false;
    int numThreads = 1;
    std::unique_ptr<OpenMM::ThreadPool> helpers;   // numThreads - 1 workers; the caller is the last
    std::vector<RigidBodyMath::BodyView> views;   // one per body, its linear flag from shapes
    /** The core's kick by these forces (none if null) over this time. */
    RigidBodyMath::Kick kickOf(const std::vector<OpenMM::Vec3>* forces, double time) const;
    /**
     * forEachBody with work(begin, end) on contiguous ranges of bodies, one per thread, which
     * returns the first failed body of its range (INT_MAX if none), and freeWork(begin, end)
     * (if given) on ranges of the free-particle list in the same parallel region: one region
     * per phase of a step instead of one per loop.
     */
    int forEachBodyRangeAndFreeParticle(const std::function<int(int, int)>& work,
                                        const std::function<void(int, int)>& freeWork);
    /** RATTLE's velocity step of every body, the core taking them four at a time. */
    void projectBodies(const double* positions, double* velocities);
    /** Call work(t) for t = 0 .. numThreads - 1, t = numThreads - 1 on the calling thread. */
    void forEachThread(const std::function<void(int)>& work);
    std::mt19937_64 collisionRandom;
    bool randomIsSet = false;
};

/** Raw 3N-double view of a Vec3 array, for the numerical core. */
inline double* coordinates(std::vector<OpenMM::Vec3>& v) {
    static_assert(sizeof(OpenMM::Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");
    return reinterpret_cast<double*>(v.data());
}

inline const double* coordinates(const std::vector<OpenMM::Vec3>& v) {
    static_assert(sizeof(OpenMM::Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");
    return reinterpret_cast<const double*>(v.data());
}

} // namespace MRattlePlugin

#endif
