#include "RigidBodyTopology.h"
#include "mrattle/RigidBodyMath.h"
#include "openmm/CMMotionRemover.h"
#include "openmm/MonteCarloAnisotropicBarostat.h"
#include "openmm/MonteCarloBarostat.h"
#include "openmm/MonteCarloMembraneBarostat.h"
#include "openmm/OpenMMException.h"
#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

std::string describeBody(int body) {
    return "Rigid body " + std::to_string(body);
}

void fail(const std::string& message) {
    throw OpenMMException(message);
}

} // namespace

void RigidBodyTopology::checkBodyDefinition(int bodyIndex, const vector<int>& particles) {
    if (particles.empty())
        fail(describeBody(bodyIndex) + " is empty: a rigid body needs at least one particle");
    std::set<int> seen;
    for (int particle : particles) {
        if (particle < 0)
            fail(describeBody(bodyIndex) + " lists particle " + std::to_string(particle) + ": particle indices cannot be negative");
        if (!seen.insert(particle).second)
            fail(describeBody(bodyIndex) + " lists particle " + std::to_string(particle) + " twice");
    }
}

RigidBodyTopology::RigidBodyTopology(const System& system, const vector<vector<int> >& explicitBodies,
                           const vector<vector<int> >& molecules) {
    readMasses(system);
    if (!explicitBodies.empty())
        checkExplicitBodies(system, explicitBodies);
    const vector<int> definitionIndex =
        assignBodies(system, explicitBodies.empty() ? massiveMembersOf(system, molecules) : explicitBodies);
    classifyConstraints(system, definitionIndex);
    hasCMMotionRemover = findCMMotionRemover(system);
    checkBarostatKeepsBodiesWhole(system, molecules, definitionIndex);
    signature = partitionSignature();
}

bool RigidBodyTopology::isMassive(const System& system, int particle) const {
    return masses[particle] != 0.0 && !system.isVirtualSite(particle);
}

void RigidBodyTopology::readMasses(const System& system) {
    const int numParticles = system.getNumParticles();
    masses.resize(numParticles);
    for (int i = 0; i < numParticles; i++) {
        masses[i] = system.getParticleMass(i);
        // A negative mass makes kinetic energy and temperature negative and the dynamics unbounded.
        if (!(masses[i] >= 0) || !std::isfinite(masses[i]))
            fail("Particle " + std::to_string(i) + " has mass " + std::to_string(masses[i]) +
                 ": a rigid-body integrator needs every mass finite and >= 0 (0 for a massless particle)");
    }
}

vector<vector<int> > RigidBodyTopology::massiveMembersOf(const System& system, const vector<vector<int> >& molecules) const {
    // Molecules, taken without virtual sites and massless particles.
    vector<vector<int> > candidates;
    for (const vector<int>& molecule : molecules) {
        vector<int> members;
        for (int i : molecule)
            if (isMassive(system, i))
                members.push_back(i);
        candidates.push_back(members);
    }
    return candidates;
}

void RigidBodyTopology::checkExplicitBodies(const System& system, const vector<vector<int> >& explicitBodies) const {
    const int numParticles = system.getNumParticles();
    vector<int> ownerBody(numParticles, -1);
    for (int b = 0; b < (int) explicitBodies.size(); b++) {
        checkBodyDefinition(b, explicitBodies[b]);
        for (int i : explicitBodies[b]) {
            if (i >= numParticles)
                fail(describeBody(b) + " lists particle " + std::to_string(i) + ", but the System has only " +
                     std::to_string(numParticles) + " particles");
            if (system.isVirtualSite(i))
                fail(describeBody(b) + " lists particle " + std::to_string(i) +
                     ", which is a virtual site: virtual sites follow their parents and cannot be body members");
            if (masses[i] == 0.0)
                fail(describeBody(b) + " lists particle " + std::to_string(i) +
                     ", which has zero mass: massless particles cannot be body members");
            if (ownerBody[i] != -1)
                fail("Particle " + std::to_string(i) + " is listed in rigid bodies " + std::to_string(ownerBody[i]) +
                     " and " + std::to_string(b) + ": a particle can belong to one body only");
            ownerBody[i] = b;
        }
    }
}

vector<int> RigidBodyTopology::assignBodies(const System& system, const vector<vector<int> >& candidates) {
    // Bodies of one particle are free particles.
    const int numParticles = system.getNumParticles();
    bodyOfParticle.assign(numParticles, -1);
    vector<int> definitionIndex;
    for (int d = 0; d < (int) candidates.size(); d++) {
        const vector<int>& members = candidates[d];
        if (members.size() < 2)
            continue;
        definitionIndex.push_back(d);
        int index = bodies.size();
        double total = 0;
        for (int i : members) {
            bodyOfParticle[i] = index;
            total += masses[i];
        }
        bodies.push_back(members);
        bodyMass.push_back(total);
    }
    for (int i = 0; i < numParticles; i++)
        if (bodyOfParticle[i] == -1 && isMassive(system, i))
            freeParticles.push_back(i);
    return definitionIndex;
}

void RigidBodyTopology::classifyConstraints(const System& system, const vector<int>& definitionIndex) {
    for (int c = 0; c < system.getNumConstraints(); c++) {
        int p1, p2;
        double distance;
        system.getConstraintParameters(c, p1, p2, distance);
        int b1 = bodyOfParticle[p1], b2 = bodyOfParticle[p2];
        if (masses[p1] == 0.0 && masses[p2] == 0.0)
            masslessConstraints++;
        else if (b1 == b2 && b1 != -1)
            ignoredConstraints++;
        else if (b1 == -1 && b2 == -1)
            freeConstraints.push_back(c);
        else {
            int inside = (b1 != -1 ? p1 : p2), outside = (b1 != -1 ? p2 : p1);
            int body = definitionIndex[b1 != -1 ? b1 : b2];
            fail("Constraint " + std::to_string(c) + " joins particle " + std::to_string(inside) + " of rigid body " +
                 std::to_string(body) + " to particle " + std::to_string(outside) +
                 " outside that body: constraints may join particles of one body or free particles only");
        }
    }
}

bool RigidBodyTopology::findCMMotionRemover(const System& system) {
    for (int f = 0; f < system.getNumForces(); f++)
        if (dynamic_cast<const CMMotionRemover*>(&system.getForce(f)) != nullptr)
            return true;
    return false;
}

void RigidBodyTopology::checkBarostatKeepsBodiesWhole(const System& system, const vector<vector<int> >& molecules,
                                                      const vector<int>& definitionIndex) const {
    // OpenMM's barostats scale each molecule's centre: a body spanning molecules would be
    // torn apart at every accepted move.
    const char* barostat = nullptr;
    for (int f = 0; f < system.getNumForces(); f++) {
        const Force* force = &system.getForce(f);
        if (dynamic_cast<const MonteCarloBarostat*>(force))
            barostat = "MonteCarloBarostat";
        else if (dynamic_cast<const MonteCarloAnisotropicBarostat*>(force))
            barostat = "MonteCarloAnisotropicBarostat";
        else if (dynamic_cast<const MonteCarloMembraneBarostat*>(force))
            barostat = "MonteCarloMembraneBarostat";
    }
    if (barostat == nullptr)
        return;
    vector<int> moleculeOf(system.getNumParticles(), -1);
    for (int m = 0; m < (int) molecules.size(); m++)
        for (int i : molecules[m])
            moleculeOf[i] = m;
    for (int b = 0; b < (int) bodies.size(); b++)
        for (int i : bodies[b])
            if (moleculeOf[i] != moleculeOf[bodies[b][0]])
                fail(describeBody(definitionIndex[b]) + " holds particles " + std::to_string(bodies[b][0]) + " and " +
                     std::to_string(i) + " of two different molecules, and the System's " + barostat +
                     " scales molecules apart, which would deform the body: make each body one molecule, or join "
                     "its parts with a bond or constraint so that OpenMM sees one molecule");
}

uint64_t RigidBodyTopology::partitionSignature() const {
    // FNV-1a hash of, for each particle, the smallest index in its body, or -1.
    vector<int32_t> representative(bodyOfParticle.size(), -1);
    for (const vector<int>& body : bodies) {
        int smallest = *std::min_element(body.begin(), body.end());
        for (int particle : body)
            representative[particle] = smallest;
    }
    uint64_t hash = 14695981039346656037ULL;
    const unsigned char* bytes = reinterpret_cast<const unsigned char*>(representative.data());
    for (size_t i = 0; i < representative.size() * sizeof(int32_t); i++) {
        hash ^= bytes[i];
        hash *= 1099511628211ULL;
    }
    return hash;
}

double RigidBodyTopology::getTranslationalDegreesOfFreedom() const {
    return 3.0 * getNumBodies() - (hasCMMotionRemover ? 3.0 - removedFromFree() : 0.0);
}

int RigidBodyTopology::getRotationalDegreesOfFreedom(int bodyDegreesOfFreedom) const {
    return bodyDegreesOfFreedom - 3 * getNumBodies();
}

double RigidBodyTopology::getFreeDegreesOfFreedom() const {
    const double unconstrained = 3.0 * freeParticles.size() - (double) freeConstraints.size();
    return unconstrained - (hasCMMotionRemover ? removedFromFree() : 0.0);
}

double RigidBodyTopology::removedFromFree() const {
    double bodies = 0, free = 0;
    for (double mass : bodyMass)
        bodies += mass;
    for (int i : freeParticles)
        free += masses[i];
    // With no massive particle at all, the 3 come off the free ones, as getNumDegreesOfFreedom() takes them.
    return bodies + free > 0 ? 3 * free / (bodies + free) : 3.0;
}

int RigidBodyTopology::getNumDegreesOfFreedom(int bodyDegreesOfFreedom) const {
    int dof = 3 * (int) freeParticles.size() - (int) freeConstraints.size() + bodyDegreesOfFreedom;
    if (hasCMMotionRemover)
        dof -= 3;
    return dof;
}

vector<RigidBodyMath::Shape> RigidBodyTopology::classifyShapes(const vector<Vec3>& positions) const {
    const double* x = reinterpret_cast<const double*>(positions.data());
    vector<RigidBodyMath::Shape> shapes(getNumBodies());
    for (int b = 0; b < getNumBodies(); b++) {
        const RigidBodyMath::BodyView body{bodies[b].data(), (int) bodies[b].size(), masses.data(), bodyMass[b], false};
        const Eigen::Vector3d center = RigidBodyMath::centerOfMass(body, x);
        shapes[b] = RigidBodyMath::classifyShape(RigidBodyMath::secondMoment(body, x, center), body.totalMass);
    }
    return shapes;
}

int RigidBodyTopology::getBodyDegreesOfFreedom(const vector<RigidBodyMath::Shape>& shapes) {
    int dof = 0;
    for (RigidBodyMath::Shape shape : shapes)
        dof += RigidBodyMath::degreesOfFreedom(shape);
    return dof;
}
