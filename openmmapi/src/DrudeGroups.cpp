#include "internal/DrudeGroups.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <Eigen/Dense>
#include <map>
#include <string>
#ifdef MRATTLE_HAVE_DRUDE
#include "openmm/DrudeForce.h"
#endif

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

vector<std::pair<int, int> > DrudeGroups::drudePairs(const System& system) {
    vector<std::pair<int, int> > found;
#ifdef MRATTLE_HAVE_DRUDE
    for (int f = 0; f < system.getNumForces(); f++)
        if (const auto* drude = dynamic_cast<const DrudeForce*>(&system.getForce(f)))
            for (int k = 0; k < drude->getNumParticles(); k++) {
                int particle, core, p2, p3, p4;
                double charge, polarizability, aniso12, aniso34;
                drude->getParticleParameters(k, particle, core, p2, p3, p4, charge, polarizability, aniso12, aniso34);
                found.push_back({particle, core});
            }
#endif
    return found;
}

void DrudeGroups::requireNumDrudeParticles(const System& system, int numDrudeParticles, const char* integratorName) {
    // Counting is O(forces) a step; a pair's parameters changed in place are OpenMM's
    // updateParametersInContext's business, as for every other force.
    int count = 0;
#ifdef MRATTLE_HAVE_DRUDE
    for (int f = 0; f < system.getNumForces(); f++)
        if (const auto* drude = dynamic_cast<const DrudeForce*>(&system.getForce(f)))
            count += drude->getNumParticles();
#endif
    if (count != numDrudeParticles)
        throw OpenMMException(std::string(integratorName) + ": the System has " + std::to_string(count) +
                              " Drude particles but had " + std::to_string(numDrudeParticles) +
                              " when the Context was created (a DrudeForce added or changed since), which the "
                              "Context does not see; call Context.reinitialize()");
}

DrudeGroups::DrudeGroups(const System& system, const RigidBodyTopology& topology, const char* integratorName) {
    const std::string name(integratorName);
    pairs = drudePairs(system);
    const int n = system.getNumParticles();
    grouped.assign(n, false);
    vector<bool> isDrude(n, false);
    for (const auto& pair : pairs) {
        const int drude = pair.first, core = pair.second;
        if (isDrude[drude])
            throw OpenMMException(name + ": particle " + std::to_string(drude) +
                                  " is the Drude particle of two pairs of the DrudeForce");
        isDrude[drude] = true;
        if (topology.getBodyOfParticle(drude) >= 0)
            throw OpenMMException(name + ": Drude particle " + std::to_string(drude) + " is in rigid body " +
                                  std::to_string(topology.getBodyOfParticle(drude)) +
                                  "; a Drude particle moves relative to its core and cannot be a body member (declare "
                                  "the bodies with addRigidBody(), without the Drude particles; their cores may be members)");
        if (system.getParticleMass(drude) == 0 || system.getParticleMass(core) == 0)
            throw OpenMMException(name + ": the Drude pair of particle " + std::to_string(drude) + " and core " +
                                  std::to_string(core) + " has a particle without mass; both need one");
    }
    for (const auto& pair : pairs)
        if (isDrude[pair.second])
            throw OpenMMException(name + ": particle " + std::to_string(pair.second) +
                                  " is both a Drude particle and the core of Drude particle " +
                                  std::to_string(pair.first));
    // One group per body with a Drude core, one per free core; each gets its Drude particles.
    std::map<int, int> groupOfBody, groupOfFreeCore;
    for (const auto& pair : pairs) {
        const int body = topology.getBodyOfParticle(pair.second);
        std::map<int, int>& index = (body >= 0 ? groupOfBody : groupOfFreeCore);
        const int key = (body >= 0 ? body : pair.second);
        auto found = index.find(key);
        if (found == index.end()) {
            Group group;
            group.rotates = (body >= 0);
            group.particles = (body >= 0 ? topology.getBodyParticles(body) : vector<int>{pair.second});
            group.places = group.particles;
            found = index.insert({key, (int) groups.size()}).first;
            groups.push_back(group);
        }
        groups[found->second].particles.push_back(pair.first);
        groups[found->second].places.push_back(pair.second);
    }
    for (const Group& group : groups)
        for (int i : group.particles)
            grouped[i] = true;
}

void DrudeGroups::rigidPart(const Group& group, const vector<Vec3>& x, const vector<Vec3>& v,
                            const vector<double>& masses, vector<Vec3>& out) {
    // V = P / M; for an augmented body also w = I^+ L about the centre of mass, both with each
    // particle at its place, a Drude particle at its core (the pseudo-inverse: a linear group
    // has no rotation about its axis).
    const size_t size = group.particles.size();
    double total = 0;
    Vec3 center, momentum;
    for (size_t k = 0; k < size; k++) {
        const int i = group.particles[k];
        total += masses[i];
        center += x[group.places[k]] * masses[i];
        momentum += v[i] * masses[i];
    }
    center /= total;
    const Vec3 velocity = momentum / total;
    Vec3 omega;
    if (group.rotates) {
        Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
        Eigen::Vector3d angular = Eigen::Vector3d::Zero();
        for (size_t k = 0; k < size; k++) {
            const int i = group.particles[k];
            const Vec3 r = x[group.places[k]] - center, u = v[i] - velocity;
            const Eigen::Vector3d a(r[0], r[1], r[2]);
            inertia += masses[i] * (a.squaredNorm() * Eigen::Matrix3d::Identity() - a * a.transpose());
            const Vec3 l = r.cross(u) * masses[i];
            angular += Eigen::Vector3d(l[0], l[1], l[2]);
        }
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(inertia);
        const Eigen::Vector3d values = solver.eigenvalues();
        const double floor = 1e-12 * values.cwiseAbs().maxCoeff();
        Eigen::Vector3d w = Eigen::Vector3d::Zero();
        for (int k = 0; k < 3; k++)
            if (values[k] > floor)
                w += solver.eigenvectors().col(k) * (solver.eigenvectors().col(k).dot(angular) / values[k]);
        omega = Vec3(w[0], w[1], w[2]);
    }
    for (size_t k = 0; k < size; k++)
        out[group.particles[k]] = velocity + omega.cross(x[group.places[k]] - center);
}

void DrudeGroups::scaleRelativeMotion(ContextImpl& context, const RigidBodyTopology& topology, const char* integratorName,
                                      double factor, vector<Vec3>& v) {
    const System& system = context.getSystem();
    const DrudeGroups groups(system, topology, integratorName);
    vector<Vec3> x, rigid(v.size());
    context.getPositions(x);
    vector<double> masses(system.getNumParticles());
    for (int i = 0; i < system.getNumParticles(); i++)
        masses[i] = system.getParticleMass(i);
    for (const Group& group : groups.groups) {
        rigidPart(group, x, v, masses, rigid);
        for (int i : group.particles)
            v[i] = rigid[i] + (v[i] - rigid[i]) * factor;
    }
}

double DrudeGroups::relativeKineticEnergy(const vector<Vec3>& x, const vector<Vec3>& v,
                                          const vector<double>& masses) const {
    vector<Vec3> rigid(v.size());
    double energy = 0;
    for (const Group& group : groups) {
        rigidPart(group, x, v, masses, rigid);
        for (int i : group.particles) {
            const Vec3 c = v[i] - rigid[i];
            energy += 0.5 * masses[i] * c.dot(c);
        }
    }
    return energy;
}

double DrudeGroups::drudeTemperature(double relativeKineticEnergy, int numDrudes) {
    return numDrudes == 0 ? 0.0 : 2 * relativeKineticEnergy / (3 * numDrudes * BOLTZ);
}

double DrudeGroups::bodyTemperature(double kineticEnergy, double relativeKineticEnergy, int dof, int numDrudes) {
    const int bodyDof = dof - 3 * numDrudes;
    return bodyDof <= 0 ? 0.0 : 2 * (kineticEnergy - relativeKineticEnergy) / (bodyDof * BOLTZ);
}
