#include "ReferenceRigidBodyOperations.h"
#include "internal/ThermalVelocities.h"
#include "openmm/AndersenThermostat.h"
#include "openmm/OpenMMException.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <istream>
#include <sstream>
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

/**
 * A checkpoint of format 3 framed this kernel's state again, with its length (int32,
 * native-endian) before the text: skip that frame if the stream starts with one. The text
 * of a random state starts with a digit, so its first four bytes read as a length are at
 * least 0x30303030: never the length of the rest, which is how a frame is told apart.
 */
void skipFormat3Frame(std::istream& stream) {
    const std::streampos start = stream.tellg();
    stream.seekg(0, std::ios::end);
    const std::streamoff rest = stream.tellg() - start;
    stream.seekg(start);
    int32_t length = -1;
    if (rest >= (std::streamoff) sizeof(length))
        stream.read(reinterpret_cast<char*>(&length), sizeof(length));
    if (!(length >= 0 && length == rest - (std::streamoff) sizeof(length)))
        stream.seekg(start);
}

} // namespace

ReferenceRigidBodyOperations::ReferenceRigidBodyOperations(const System& system, const RigidBodyTopology& topology)
    : bodies(topology) {
    const int n = system.getNumParticles();
    inverseMass.resize(n);
    for (int i = 0; i < n; i++) {
        double mass = system.getParticleMass(i);
        inverseMass[i] = (mass == 0.0 ? 0.0 : 1.0 / mass);
    }
    shapes.assign(bodies.getNumBodies(), RigidBodyMath::Shape::General);
    for (int b = 0; b < bodies.getNumBodies(); b++) {
        const vector<int>& atoms = bodies.getBodyParticles(b);
        views.push_back(RigidBodyMath::BodyView{atoms.data(), (int) atoms.size(), bodies.getMasses().data(),
                                                bodies.getBodyMass(b), false});
    }
    vector<bool> free(n, false);
    for (int i : bodies.getFreeParticles())
        free[i] = true;
    for (int i = 0; i < n; i++)
        if (bodies.getBodyOfParticle(i) < 0 && !free[i])
            otherParticles.push_back(i);
    if (!bodies.getFreeConstraints().empty()) {
        // OpenMM's constraint code (CCMA, SETTLE for rigid water) on the free constraints only.
        System freeSystem;
        for (int i = 0; i < n; i++)
            freeSystem.addParticle(system.getParticleMass(i));
        for (int c : bodies.getFreeConstraints()) {
            int p1, p2;
            double distance;
            system.getConstraintParameters(c, p1, p2, distance);
            freeSystem.addConstraint(p1, p2, distance);
            freeConstraintAtoms.push_back({p1, p2});
            freeConstraintDistances.push_back(distance);
        }
        freeConstraints.reset(new ReferenceConstraints(freeSystem));
    }
    for (int f = 0; f < system.getNumForces(); f++)
        if (const AndersenThermostat* thermostat = dynamic_cast<const AndersenThermostat*>(&system.getForce(f))) {
            andersen = true;
            int seed = thermostat->getRandomNumberSeed();
            collisionRandom.seed(seed != 0 ? (uint64_t) seed : (uint64_t) std::random_device()());
            randomIsSet = true;
        }
}

RigidBodyMath::Kick ReferenceRigidBodyOperations::kickOf(const vector<Vec3>* forces, double time) const {
    RigidBodyMath::Kick kick;
    if (forces != nullptr) {
        kick.forces = coordinates(*forces);
        kick.inverseMasses = inverseMass.data();
        kick.time = time;
    }
    return kick;
}

void ReferenceRigidBodyOperations::setThreads(int count) {
    numThreads = std::max(count, 1);
    if (numThreads > 1)
        helpers.reset(new ThreadPool(numThreads - 1));
    else
        helpers.reset();
}

void ReferenceRigidBodyOperations::forEachThread(const std::function<void(int)>& work) {
    // The calling thread takes a share instead of sleeping until the helpers finish. Waking
    // all the workers of a pool at once lets the scheduler put two of them on the one idle
    // core while the caller's core then idles (measured: 2 threads no faster than 1 on 2
    // cores); a caller that keeps working keeps its core busy.
    helpers->execute([&](ThreadPool&, int thread) { work(thread); });
    try {
        work(numThreads - 1);
    } catch (...) {
        helpers->waitForThreads();  // the helpers still use work's captures
        throw;
    }
    helpers->waitForThreads();
}

int ReferenceRigidBodyOperations::forEachBody(const std::function<bool(int)>& work) {
    return forEachBodyRangeAndFreeParticle(
        [&](int begin, int end) {
            for (int b = begin; b < end; b++)
                if (!work(b))
                    return b;
            return INT_MAX;
        },
        nullptr);
}

int ReferenceRigidBodyOperations::forEachBodyRangeAndFreeParticle(const std::function<int(int, int)>& work,
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

void ReferenceRigidBodyOperations::forEachParticleRange(const std::function<void(int, int)>& work) {
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

void ReferenceRigidBodyOperations::updateShapes(const vector<Vec3>& positions) {
    shapes = bodies.classifyShapes(positions);
    // A point rotates no more than a line does: both take the linear body's arithmetic.
    for (int b = 0; b < bodies.getNumBodies(); b++)
        views[b].linear = (shapes[b] != RigidBodyMath::Shape::General);
}

int ReferenceRigidBodyOperations::getBodyDegreesOfFreedom() const {
    return RigidBodyTopology::getBodyDegreesOfFreedom(shapes);
}

void ReferenceRigidBodyOperations::seedRandom(int seed) {
    if (randomIsSet)
        return;
    collisionRandom.seed(seed != 0 ? (uint64_t) seed : (uint64_t) std::random_device()());
    randomIsSet = true;
}

void ReferenceRigidBodyOperations::driftAndReset(vector<Vec3>& x, const vector<Vec3>& v, double h, double tolerance,
                                               vector<Vec3>& newPositions, vector<Vec3>& newVelocities,
                                               const vector<Vec3>* forces, double kickTime) {
    // A free particle's velocity after the kick (if forces are given; free particles are massive).
    auto kicked = [&](int i) { return forces != nullptr ? v[i] + (*forces)[i] * (kickTime * inverseMass[i]) : v[i]; };
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
    const RigidBodyMath::Kick kick = kickOf(forces, kickTime);
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
            throw OpenMMException("particle " + std::to_string(i) +
                                  " would move to a position that is not finite; its force or velocity is not finite");
    }
    if (failed != INT_MAX)
        throw OpenMMException("the position reset of rigid body " + std::to_string(failed) + " found no rotation in " +
                              std::to_string(RigidBodyMath::MaxRotationIterations) +
                              " Newton iterations; the step size is too large for the forces, or they are not finite");
}

void ReferenceRigidBodyOperations::constrainFreePositions(vector<Vec3>& oldPositions, vector<Vec3>& newPositions,
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

void ReferenceRigidBodyOperations::constrainFreeVelocities(vector<Vec3>& positions, vector<Vec3>& velocities,
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

void ReferenceRigidBodyOperations::projectVelocities(vector<Vec3>& positions, vector<Vec3>& velocities, double tolerance) {
    constrainFreeVelocities(positions, velocities, tolerance);
    projectBodies(coordinates(positions), coordinates(velocities));
}

void ReferenceRigidBodyOperations::projectBodies(const double* positions, double* velocities) {
    forEachBodyRangeAndFreeParticle(
        [&](int begin, int end) {
            RigidBodyMath::kickAndProjectBodiesVelocities(views.data() + begin, end - begin, RigidBodyMath::Kick(),
                                                          positions, velocities);
            return INT_MAX;
        },
        nullptr);
}

void ReferenceRigidBodyOperations::projectNonRigidVelocities(vector<Vec3>& positions, vector<Vec3>& velocities,
                                                           double tolerance) {
    constrainFreeVelocities(positions, velocities, tolerance);
    const double* x = coordinates(positions);
    double* v = coordinates(velocities);
    forEachBody([&](int b) {
        RigidBodyMath::projectNonRigidBodyVelocities(view(b), x, v, RigidBodyMath::RigidVelocityTolerance);
        return true;
    });
}

void ReferenceRigidBodyOperations::kick(vector<Vec3>& velocities, const vector<Vec3>& forces, double time) {
    // Massless particles (virtual sites too) take no kick.
    forEachParticleRange([&](int begin, int end) {
        for (int i = begin; i < end; i++)
            if (inverseMass[i] != 0)
                velocities[i] += forces[i] * (time * inverseMass[i]);
    });
}

double ReferenceRigidBodyOperations::kineticEnergy(const vector<Vec3>& velocities) const {
    double energy = 0;
    for (size_t i = 0; i < velocities.size(); i++)
        if (inverseMass[i] != 0)
            energy += 0.5 * velocities[i].dot(velocities[i]) / inverseMass[i];
    return energy;
}

void ReferenceRigidBodyOperations::kineticEnergies(const vector<Vec3>& velocities, double& translational,
                                                 double& rotational, double& free) const {
    translational = rotational = free = 0;
    for (int b = 0; b < bodies.getNumBodies(); b++) {
        const vector<int>& atoms = bodies.getBodyParticles(b);
        Vec3 momentum;
        for (int i : atoms)   // body members are massive
            momentum += velocities[i] / inverseMass[i];
        const double mass = bodies.getBodyMass(b);
        const Vec3 center = momentum / mass;
        translational += 0.5 * mass * center.dot(center);
        for (int i : atoms) {
            const Vec3 relative = velocities[i] - center;
            rotational += 0.5 * relative.dot(relative) / inverseMass[i];
        }
    }
    for (int i : bodies.getFreeParticles())
        free += 0.5 * velocities[i].dot(velocities[i]) / inverseMass[i];
}

vector<Vec3> ReferenceRigidBodyOperations::velocitiesForTemperature(vector<Vec3>& positions, double temperature,
                                                                  int randomSeed, double tolerance) {
    // Maxwell-Boltzmann per particle, then the rigid-body projection (which keeps the
    // distribution's form on the rigid degrees of freedom), then an exact rescale to the
    // requested kinetic temperature with the rigid-body degrees of freedom.
    vector<Vec3> velocities = ThermalVelocities::maxwellBoltzmann(inverseMass, temperature, randomSeed);
    projectVelocities(positions, velocities, tolerance);
    ThermalVelocities::scaleToTemperature(bodies, inverseMass, bodies.getNumDegreesOfFreedom(getBodyDegreesOfFreedom()),
                                           temperature, velocities);
    return velocities;
}

void ReferenceRigidBodyOperations::collideBodies(vector<Vec3>& x, vector<Vec3>& v, double temperature,
                                                 double tolerance) {
    // AndersenThermostat randomizes single particles (or groups held by constraints).
    // Projecting a body of which only some atoms are fresh onto rigid motion does not keep
    // the rigid-body Boltzmann distribution (bonded water settles ~10% cold), while
    // projecting fresh Maxwell-Boltzmann velocities of all its atoms does.
    const double* positionData = coordinates(x);
    std::normal_distribution<double> gaussian(0.0, 1.0);
    for (int b = 0; b < bodies.getNumBodies(); b++) {
        if (!(RigidBodyMath::nonRigidVelocityFraction(view(b), positionData, coordinates(v)) > RigidBodyMath::CollisionThreshold))
            continue;  // still rigid: no collision
        for (int i : bodies.getBodyParticles(b)) {
            double sigma = std::sqrt(BOLTZ * temperature * inverseMass[i]);
            double gx = gaussian(collisionRandom), gy = gaussian(collisionRandom), gz = gaussian(collisionRandom);
            v[i] = Vec3(gx, gy, gz) * sigma;
        }
    }
    projectNonRigidVelocities(x, v, tolerance);
}

void ReferenceRigidBodyOperations::writeState(std::ostream& stream) const {
    // Unframed: the checkpoint header frames the kernel's state.
    stream << collisionRandom;
}

void ReferenceRigidBodyOperations::readState(std::istream& stream) {
    skipFormat3Frame(stream);
    std::mt19937_64 generator;
    stream >> generator;
    if (stream.fail())
        throw OpenMMException("the checkpoint's kernel data is malformed (its random state cannot be read)");
    collisionRandom = generator;
    randomIsSet = true;
}
