#ifndef MRATTLE_TEST_DRUDE_SYSTEM_H_
#define MRATTLE_TEST_DRUDE_SYSTEM_H_

// The Drude integrators' tests' systems (TestDrudeIntegrators.cpp, TestDrudeManyGroups.cpp,
// the fuzz harness): rigid waters with a Drude particle on each oxygen and free polarizable
// ions. Only where the build has OpenMM's Drude plugin.
#ifdef MRATTLE_HAVE_DRUDE

#include "RigidBodyIntegrator.h"
#include "TestSupport.h"
#include "openmm/Context.h"
#include "openmm/DrudeForce.h"
#include "openmm/NonbondedForce.h"
#include "openmm/System.h"
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace MRattleTest {
namespace Drude {

using namespace OpenMM;
using MRattlePlugin::RigidBodyIntegrator;
using std::vector;

/**
 * SWM4-NDP-like water without its M site (its charge on the oxygen core): rigid O-H-H
 * bodies, each with a Drude particle on the oxygen; plus free polarizable ions (a core and
 * its Drude particle). Vacuum, no cutoff (or periodic: drudeWaters); all pairs inside a
 * molecule or pair excluded.
 *
 * Each Drude particle is repelled by the other waters' hydrogens (an LJ exception, sigma 0.2
 * nm, epsilon 2 kJ/mol, their Coulomb kept): neither has LJ of its own, and without it a
 * hydrogen pulls a Drude particle far from its core (the polarization catastrophe). OpenMM's
 * hard wall (0.02 nm) does not stop that here: the Drude particle then sits at the wall and
 * each bounce adds energy (8 waters, 5/ps Langevin at 300 K, three seeds: 450-1750 K over 6 ps).
 */
struct DrudeSystem {
    System system;
    vector<Vec3> positions;
    vector<vector<int> > bodies;                   // O, H, H of each water
    vector<std::pair<int, int> > pairs;            // (Drude, core)
};

/**
 * With cutoff > 0 (below 1.5 spacing): periodic, in a cube of 3 spacings (the lattice's
 * period), NonbondedForce::CutoffPeriodic at that cutoff, and the Drude particles' repulsion
 * from other molecules' hydrogens an LJ of both of their own (sigma 0.2 nm, epsilon 2 kJ/mol,
 * which the combination rule gives their pairs) instead of exceptions, which would join all
 * the molecules into one for OpenMM: each water and each ion is then a molecule of its own,
 * which a device platform's reordering may move.
 */
inline DrudeSystem drudeWaters(int numWaters, int numIons, double spacing, double cutoff = 0) {
    DrudeSystem d;
    NonbondedForce* nonbonded = new NonbondedForce();
    const bool periodic = cutoff > 0;
    const double sigmaRepelled = periodic ? 0.2 : 1.0, epsilonRepelled = periodic ? 2.0 : 0.0;
    if (periodic) {
        nonbonded->setNonbondedMethod(NonbondedForce::CutoffPeriodic);
        nonbonded->setCutoffDistance(cutoff);
        d.system.setDefaultPeriodicBoxVectors(Vec3(3 * spacing, 0, 0), Vec3(0, 3 * spacing, 0), Vec3(0, 0, 3 * spacing));
    }
    DrudeForce* drude = new DrudeForce();
    d.system.addForce(nonbonded);
    d.system.addForce(drude);
    const double qDrude = -1.71636, alpha = 0.00097825;
    int placed = 0;
    auto site = [&](int k) {
        // A cubic lattice of 3 sites per side, centred on the origin.
        return Vec3(k % 3 - 1.0, (k / 3) % 3 - 1.0, k / 9 - 1.0) * spacing;
    };
    for (int w = 0; w < numWaters; w++) {
        const Vec3 o = site(placed++);
        const int first = d.system.getNumParticles();
        d.system.addParticle(15.59943);   // O core (15.9994 less the Drude's 0.4)
        d.system.addParticle(1.008);
        d.system.addParticle(1.008);
        d.system.addParticle(0.4);        // the Drude particle
        nonbonded->addParticle(-1.11466 + 1.71636, 0.318395, 0.882573);
        nonbonded->addParticle(0.55733, sigmaRepelled, epsilonRepelled);
        nonbonded->addParticle(0.55733, sigmaRepelled, epsilonRepelled);
        nonbonded->addParticle(qDrude, sigmaRepelled, epsilonRepelled);
        // Geometry: O-H 0.09572 nm, H-O-H 104.52 degrees, turned by w.
        const double half = 0.5 * 104.52 * M_PI / 180, turn = 0.7 * w;
        const Vec3 h1(0.09572 * std::sin(half), 0.09572 * std::cos(half), 0);
        const Vec3 h2(-0.09572 * std::sin(half), 0.09572 * std::cos(half), 0);
        auto turned = [&](const Vec3& v) {
            return Vec3(v[0] * std::cos(turn) - v[2] * std::sin(turn), v[1], v[0] * std::sin(turn) + v[2] * std::cos(turn));
        };
        d.positions.push_back(o);
        d.positions.push_back(o + turned(h1));
        d.positions.push_back(o + turned(h2));
        d.positions.push_back(o + Vec3(0.001, -0.0005, 0.0007));
        for (int i = first; i < first + 4; i++)
            for (int j = i + 1; j < first + 4; j++)
                nonbonded->addException(i, j, 0.0, 1.0, 0.0);
        drude->addParticle(first + 3, first, -1, -1, -1, qDrude, alpha, 1.0, 1.0);
        d.bodies.push_back({first, first + 1, first + 2});
        d.pairs.push_back({first + 3, first});
    }
    for (int k = 0; k < numIons; k++) {
        const Vec3 x = site(placed++);
        const int core = d.system.addParticle(35.0), particle = d.system.addParticle(0.4);
        nonbonded->addParticle(1.2, 0.40, 0.5);
        nonbonded->addParticle(-1.2, sigmaRepelled, epsilonRepelled);
        nonbonded->addException(core, particle, 0.0, 1.0, 0.0);
        d.positions.push_back(x);
        d.positions.push_back(x + Vec3(-0.0008, 0.0006, 0.0004));
        drude->addParticle(particle, core, -1, -1, -1, -1.2, 0.002, 1.0, 1.0);
        d.pairs.push_back({particle, core});
    }
    if (periodic)
        return d;
    for (const auto& pair : d.pairs)
        for (const vector<int>& body : d.bodies)
            if (std::find(body.begin(), body.end(), pair.second) == body.end())
                for (int h : {body[1], body[2]}) {
                    double qH, qDrude, sigma, epsilon;
                    nonbonded->getParticleParameters(h, qH, sigma, epsilon);
                    nonbonded->getParticleParameters(pair.first, qDrude, sigma, epsilon);
                    nonbonded->addException(h, pair.first, qH * qDrude, 0.2, 2.0);
                }
    return d;
}

/**
 * Adds numBlobs rigid bodies of `atoms` uncharged atoms in a flattened ball 0.8 nm across, 2 nm
 * apart along x from 2.5 nm, with a Drude particle 0.003-0.006 nm off every tenth atom: each a
 * Drude group of more than the device's large-body threshold (64 particles) for atoms >= 60.
 */
inline void addPolarizableBlobs(DrudeSystem& d, int numBlobs, int atoms) {
    NonbondedForce* nonbonded = nullptr;
    DrudeForce* drude = nullptr;
    for (int f = 0; f < d.system.getNumForces(); f++) {
        if (NonbondedForce* n = dynamic_cast<NonbondedForce*>(&d.system.getForce(f)))
            nonbonded = n;
        if (DrudeForce* n = dynamic_cast<DrudeForce*>(&d.system.getForce(f)))
            drude = n;
    }
    unsigned int state = 12345;
    auto uniform = [&]() {  // in [-1, 1): the same on every platform and compiler
        state = state * 1103515245u + 12345u;
        return ((state >> 8) & 0xFFFF) / 32768.0 - 1.0;
    };
    for (int b = 0; b < numBlobs; b++) {
        vector<int> body;
        const Vec3 center(2.5 + 2.0 * b, 0, 0);
        for (int k = 0; k < atoms; k++) {
            const int atom = d.system.addParticle(12.0 + 4.0 * (k % 2));
            nonbonded->addParticle(0.0, 1.0, 0.0);
            const Vec3 x = center + Vec3(uniform(), uniform(), 0.5 * uniform()) * 0.4;
            d.positions.push_back(x);
            body.push_back(atom);
            if (k % 10 == 0) {
                const int particle = d.system.addParticle(0.4);
                nonbonded->addParticle(0.0, 1.0, 0.0);
                const Vec3 offset(uniform(), uniform(), uniform());
                d.positions.push_back(x + offset * (0.0045 + 0.0015 * uniform()) / std::sqrt(offset.dot(offset)));
                drude->addParticle(particle, atom, -1, -1, -1, -1.71636, 0.00097825, 1.0, 1.0);
                d.pairs.push_back({particle, atom});
            }
        }
        d.bodies.push_back(body);
    }
}

/** A Context of the system on a platform with these properties, its waters declared as bodies to the integrator. */
inline std::unique_ptr<Context> platformContext(const DrudeSystem& d, RigidBodyIntegrator& integrator,
                                                const std::string& platformName,
                                                const std::map<std::string, std::string>& properties = {}) {
    for (const vector<int>& body : d.bodies)
        integrator.addRigidBody(body);
    std::unique_ptr<Context> context(new Context(d.system, integrator, platform(platformName), properties));
    context->setPositions(d.positions);
    return context;
}

/** A Reference Context of the system with its waters declared as bodies to the integrator. */
inline std::unique_ptr<Context> referenceContext(const DrudeSystem& d, RigidBodyIntegrator& integrator) {
    return platformContext(d, integrator, "Reference");
}

/** The largest distance of a Drude particle from its core. */
inline double farthestDrude(const DrudeSystem& d, const vector<Vec3>& positions) {
    double farthest = 0;
    for (const auto& pair : d.pairs) {
        const Vec3 delta = positions[pair.first] - positions[pair.second];
        farthest = std::max(farthest, std::sqrt(delta.dot(delta)));
    }
    return farthest;
}

inline double distance(const Vec3& a, const Vec3& b) {
    const Vec3 d = a - b;
    return std::sqrt(d.dot(d));
}


} // namespace Drude
} // namespace MRattleTest

#endif // MRATTLE_HAVE_DRUDE

#endif
