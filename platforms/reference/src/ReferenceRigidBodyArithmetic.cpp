#include "ReferenceRigidBodyState.h"
#include "mrattle/RigidBodyRotor.h"
#include "openmm/OpenMMException.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <algorithm>
#include <cmath>
#include <climits>
#include <string>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

/**
 * A free constraint is refused when its error exceeds this many times the tolerance (CCMA
 * stops within 1x when it converges; the slack is for round-off, SETTLE's included).
 */
const double ConstraintCheckSlack = 2;

/** Raw 3N-double view of a Vec3 array, for the numerical core. */
double* coordinates(vector<Vec3>& v) {
    static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");
    return reinterpret_cast<double*>(v.data());
}

const double* coordinates(const vector<Vec3>& v) {
    return reinterpret_cast<const double*>(v.data());
}

} // namespace

RigidBodyMath::Kick ReferenceRigidBodyState::kickOf(const vector<Vec3>* forces, double time) const {
    RigidBodyMath::Kick kick;
    if (forces != nullptr) {
        kick.forces = coordinates(*forces);
        kick.inverseMasses = inverseMass.data();
        kick.time = time;
    }
    return kick;
}

void ReferenceRigidBodyState::setThreads(int count) {
    numThreads = std::max(count, 1);
    if (numThreads > 1)
        helpers.reset(new ThreadPool(numThreads - 1));
    else
        helpers.reset();
}

void ReferenceRigidBodyState::forEachThread(const std::function<void(int)>& work) {
    // The calling thread takes a share instead of sleeping until the helpers finish: a caller
    // that keeps working keeps its core busy, where waking every worker can leave it idle.
    helpers->execute([&](ThreadPool&, int thread) { work(thread); });
    try {
        work(numThreads - 1);
    } catch (...) {
        helpers->waitForThreads();  // the helpers still use work's captures
        throw;
    }
    helpers->waitForThreads();
}

int ReferenceRigidBodyState::forEachBody(const std::function<bool(int)>& work) {
    return forEachBodyRangeAndFreeParticle(
        [&](int begin, int end) {
            for (int b = begin; b < end; b++)
                if (!work(b))
                    return b;
            return INT_MAX;
        },
        nullptr);
}

int ReferenceRigidBodyState::forEachBodyRangeAndFreeParticle(const std::function<int(int, int)>& work,
                                                                const std::function<void(int, int)>& freeWork) {
    const int numBodies = bodies.getNumBodies();
    const int numFree = bodies.getFreeParticles().size();
    // A parallel region costs microseconds, a body a fraction of one: only many bodies pay.
    if (numThreads == 1 || numBodies < 256) {
        if (freeWork)
            freeWork(0, numFree);
        return work(0, numBodies);
    }
    vector<int> firstFailure(numThreads, INT_MAX);
    forEachThread([&](int thread) {
        if (freeWork)
            freeWork((long long) numFree * thread / numThreads, (long long) numFree * (thread + 1) / numThreads);
        firstFailure[thread] = work((long long) numBodies * thread / numThreads,
                                    (long long) numBodies * (thread + 1) / numThreads);
    });
    return *std::min_element(firstFailure.begin(), firstFailure.end());
}

void ReferenceRigidBodyState::forEachParticleRange(const std::function<void(int, int)>& work) {
    const int numParticles = inverseMass.size();
    // A particle costs nanoseconds: only large systems pay for a parallel region.
    if (numThreads == 1 || numParticles < 4096) {
        work(0, numParticles);
        return;
    }
    forEachThread([&](int thread) {
        work((long long) numParticles * thread / numThreads, (long long) numParticles * (thread + 1) / numThreads);
    });
}

void ReferenceRigidBodyState::driftAndReset(double kickTime, double h, double tolerance) {
    // Into the step buffers, which then become the state: a body that finds no rotation
    // leaves the Context as it was.
    phase([&] {
        vector<Vec3>& x = positions();
        const vector<Vec3>& v = velocities();
        const vector<Vec3>* kickForces = (kickTime != 0 ? &forces() : nullptr);
        vector<Vec3>& newPositions = nextPositions;
        vector<Vec3>& newVelocities = nextVelocities;
        // A free particle's velocity after the kick (if forces are given; free particles are massive).
        auto kicked = [&](int i) {
            return kickForces != nullptr ? v[i] + (*kickForces)[i] * (kickTime * inverseMass[i]) : v[i];
        };
        for (int i : otherParticles) {   // massless: they do not move by themselves
            newVelocities[i] = v[i];
            newPositions[i] = x[i];
        }
        // One parallel region: free particles' drifts (their velocities come from the constrained
        // displacement below), and each body's kick, drift and reset in the same passes over its
        // atoms (the body's new positions and velocities are formed from displacements).
        const vector<int>& freeParticles = bodies.getFreeParticles();
        const double* oldPositions = coordinates(x);
        const double* oldVelocities = coordinates(v);
        double* velocitiesOut = coordinates(newVelocities);
        double* positionsOut = coordinates(newPositions);
        const RigidBodyMath::Kick kick = kickOf(kickForces, kickTime);
        const int failed = forEachBodyRangeAndFreeParticle(
            [&](int begin, int end) {
                const int failed = RigidBodyMath::kickDriftAndResetBodies(views.data() + begin, end - begin, kick, h,
                                                                          oldPositions, oldVelocities, positionsOut,
                                                                          velocitiesOut);
                return failed < end - begin ? begin + failed : INT_MAX;
            },
            [&](int begin, int end) {
                for (int k = begin; k < end; k++) {
                    const int i = freeParticles[k];
                    newPositions[i] = x[i] + kicked(i) * h;
                }
            });
        // Free particles: RATTLE for their constraints, velocities from the displacement.
        constrainFreePositions(x, newPositions, tolerance);
        const double inverseStep = 1.0 / h;
        for (int i : freeParticles) {
            newVelocities[i] = (newPositions[i] - x[i]) * inverseStep;
            if (!std::isfinite(newPositions[i][0] + newPositions[i][1] + newPositions[i][2] + newVelocities[i][0] +
                               newVelocities[i][1] + newVelocities[i][2]))
                throw OpenMMException("particle " + std::to_string(i) + " would move to a position that is not "
                                      "finite; its force or velocity is not finite");
        }
        if (failed != INT_MAX)
            throw OpenMMException("the position reset of rigid body " + std::to_string(failed) +
                                  " found no rotation in " + std::to_string(RigidBodyMath::MaxRotationIterations) +
                                  " Newton iterations; the step size is too large for the forces, or they are not "
                                  "finite");
        acceptNewState();
    });
}

void ReferenceRigidBodyState::constrainFreePositions(vector<Vec3>& oldPositions, vector<Vec3>& newPositions,
                                                        double tolerance) {
    if (!freeConstraints)
        return;
    freeConstraints->apply(oldPositions, newPositions, inverseMass, tolerance);
    // OpenMM's CCMA stops after its iteration limit without saying so: check what it left.
    for (size_t c = 0; c < freeConstraintDistances.size(); c++) {
        const Vec3 d = newPositions[freeConstraintAtoms[c].first] - newPositions[freeConstraintAtoms[c].second];
        const double length = std::sqrt(d.dot(d)), target = freeConstraintDistances[c];
        if (!(std::fabs(length - target) <= ConstraintCheckSlack * tolerance * target))
            throw OpenMMException("the constraint between free particles " + std::to_string(freeConstraintAtoms[c].first) +
                                  " and " + std::to_string(freeConstraintAtoms[c].second) + " did not converge (" +
                                  std::to_string(length) + " nm instead of " + std::to_string(target) +
                                  " nm); the step size is too large for the velocities or forces");
    }
}

void ReferenceRigidBodyState::constrainFreeVelocities(vector<Vec3>& positions, vector<Vec3>& velocities,
                                                         double tolerance) {
    if (!freeConstraints)
        return;
    freeConstraints->applyToVelocities(positions, velocities, inverseMass, tolerance);
    // The same criterion as CCMA's velocity step (2 mu |dv . r| / r^2 within the tolerance).
    for (size_t c = 0; c < freeConstraintDistances.size(); c++) {
        const int a = freeConstraintAtoms[c].first, b = freeConstraintAtoms[c].second;
        const Vec3 r = positions[a] - positions[b];
        const double reducedMass = 1.0 / (inverseMass[a] + inverseMass[b]);
        const double error = std::fabs(reducedMass * (velocities[a] - velocities[b]).dot(r) / r.dot(r));
        if (!(error <= ConstraintCheckSlack * tolerance))
            throw OpenMMException("the velocity constraint between free particles " + std::to_string(a) + " and " +
                                  std::to_string(b) + " did not converge");
    }
}

void ReferenceRigidBodyState::projectArrays(vector<Vec3>& positions, vector<Vec3>& velocities, double tolerance) {
    constrainFreeVelocities(positions, velocities, tolerance);
    const double* x = coordinates(positions);
    double* v = coordinates(velocities);
    // The core takes the bodies four at a time.
    forEachBodyRangeAndFreeParticle(
        [&](int begin, int end) {
            RigidBodyMath::kickAndProjectBodiesVelocities(views.data() + begin, end - begin, RigidBodyMath::Kick(), x,
                                                          v);
            return INT_MAX;
        },
        nullptr);
}

void ReferenceRigidBodyState::projectNonRigidArrays(vector<Vec3>& positions, vector<Vec3>& velocities,
                                                    double tolerance) {
    constrainFreeVelocities(positions, velocities, tolerance);
    const double* x = coordinates(positions);
    double* v = coordinates(velocities);
    forEachBody([&](int b) {
        RigidBodyMath::projectNonRigidBodyVelocities(views[b], x, v, RigidBodyMath::RigidVelocityTolerance);
        return true;
    });
}

void ReferenceRigidBodyState::kick(double time) {
    vector<Vec3>& v = velocities();
    const vector<Vec3>& f = forces();
    // Massless particles (virtual sites too) take no kick.
    forEachParticleRange([&](int begin, int end) {
        for (int i = begin; i < end; i++)
            if (inverseMass[i] != 0)
                v[i] += f[i] * (time * inverseMass[i]);
    });
}

double ReferenceRigidBodyState::kineticEnergyOf(const vector<Vec3>& velocities) const {
    double energy = 0;
    for (size_t i = 0; i < velocities.size(); i++)
        if (inverseMass[i] != 0)
            energy += 0.5 * velocities[i].dot(velocities[i]) / inverseMass[i];
    return energy;
}

void ReferenceRigidBodyState::collideBodies(vector<Vec3>& x, vector<Vec3>& v, double temperature,
                                                 double tolerance) {
    // AndersenThermostat randomizes single particles (or groups held by constraints).
    // Projecting a body of which only some atoms are fresh onto rigid motion does not keep
    // the rigid-body Boltzmann distribution (bonded water settles ~10% cold), while
    // projecting fresh Maxwell-Boltzmann velocities of all its atoms does.
    const double* positionData = coordinates(x);
    std::normal_distribution<double> gaussian(0.0, 1.0);
    for (int b = 0; b < bodies.getNumBodies(); b++) {
        if (!(RigidBodyMath::nonRigidVelocityFraction(views[b], positionData, coordinates(v)) > RigidBodyMath::CollisionThreshold))
            continue;  // still rigid: no collision
        for (int i : bodies.getBodyParticles(b)) {
            double sigma = std::sqrt(BOLTZ * temperature * inverseMass[i]);
            double gx = gaussian(random), gy = gaussian(random), gz = gaussian(random);
            v[i] = Vec3(gx, gy, gz) * sigma;
        }
    }
    projectNonRigidArrays(x, v, tolerance);
}

void ReferenceRigidBodyState::scaleVelocities(double factor) {
    for (Vec3& velocity : velocities())
        velocity *= factor;
}

void ReferenceRigidBodyState::addNoise(double friction, double temperature, double h) {
    // Followed by project(): projected Gaussian noise is the noise on the rigid degrees of freedom.
    vector<Vec3>& v = velocities();
    const double a = std::exp(-friction * h);
    const double kT = BOLTZ * temperature;
    std::normal_distribution<double> gaussian(0.0, 1.0);
    for (size_t i = 0; i < v.size(); i++)
        if (inverseMass[i] != 0) {
            const double sigma = std::sqrt((1 - a * a) * kT * inverseMass[i]);
            const double gx = gaussian(random), gy = gaussian(random), gz = gaussian(random);
            v[i] = v[i] * a + Vec3(gx, gy, gz) * sigma;
        }
}

void ReferenceRigidBodyState::rotorDriftAndReset(double h, double tolerance) {
    phase([&] {
        vector<Vec3>& x = positions();
        vector<Vec3>& v = velocities();
        const vector<Vec3>& f = forces();
        const int n = x.size();
        // Free particles: half kick and drift, then RATTLE for their constraints (body atoms
        // are overwritten below; they take no part in free constraints).
        for (int i = 0; i < n; i++)
            nextPositions[i] = (inverseMass[i] != 0 ? x[i] + (v[i] + f[i] * (0.5 * h * inverseMass[i])) * h : x[i]);
        constrainFreePositions(x, nextPositions, tolerance);
        const int failed = forEachBody([&](int b) {
            return RigidBodyRotor::positionStep(views[b], coordinates(x), coordinates(v), coordinates(f), h,
                                                coordinates(nextPositions), coordinates(nextVelocities));
        });
        if (failed != INT_MAX)
            throw OpenMMException("rigid body " + std::to_string(failed) +
                                  " would turn by more than a quarter turn in one step, or its motion is not finite; "
                                  "the step size is too large for the forces, or they are not finite");
        // Free particles: refuse what is not finite, as for bodies (the Context is not yet changed).
        for (int i : bodies.getFreeParticles())
            if (!std::isfinite(nextPositions[i][0] + nextPositions[i][1] + nextPositions[i][2]))
                throw OpenMMException("particle " + std::to_string(i) +
                                      " would move to a position that is not finite; the forces are not finite");
        // Free particles' velocities from their displacement (massless ones keep theirs).
        const double inverseStep = 1.0 / h;
        for (int i = 0; i < n; i++) {
            if (inverseMass[i] == 0)
                nextVelocities[i] = v[i];
            else if (bodies.getBodyOfParticle(i) < 0)
                nextVelocities[i] = (nextPositions[i] - x[i]) * inverseStep;
        }
        acceptNewState();
    });
}
