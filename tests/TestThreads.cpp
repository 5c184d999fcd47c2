/*
 * On the CPU platform the per-body and per-atom work is split over the platform's Threads.
 * Each body and atom is computed the same way whichever thread takes it: with only a
 * per-particle external force (so OpenMM's own threaded force sums play no part) the
 * trajectory is bit for bit the same with 1 and 2 threads, for every integrator there.
 */
#include "openmm/CustomExternalForce.h"
#include "MRattleLangevinIntegrator.h"
#include "TestSupport.h"
#include <gtest/gtest.h>
#include <cmath>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

TEST(Threads, BodiesGiveTheSameTrajectoryWithOneAndTwoThreads) {
    // 1024 tetrahedral bodies, 5120 atoms: more than the 256 bodies and 4096 atoms below
    // which the work stays on one thread. A harmonic well makes the kicks matter.
    Molecule m = tetrahedral();
    System system;
    vector<Vec3> positions, velocities;
    vector<vector<int> > bodies;
    CustomExternalForce* well = new CustomExternalForce("0.5*(x^2+y^2+z^2)");
    system.addForce(well);
    for (int b = 0; b < 1024; b++) {
        vector<Vec3> rotation = randomRotation(100 + b);
        vector<int> body;
        const Vec3 center(0.6 * (b % 8), 0.6 * ((b / 8) % 8), 0.6 * (b / 64) - 4.0);
        const Vec3 spin(0.3 * std::sin(b), 2.0 * std::cos(0.7 * b), 1.0);
        for (size_t i = 0; i < m.sites.size(); i++) {
            body.push_back(system.addParticle(m.masses[i]));
            well->addParticle(body.back());
            Vec3 a = rotate(rotation, m.sites[i]);
            positions.push_back(center + a);
            velocities.push_back(Vec3(0.1, -0.2, 0.05) + spin.cross(a));
        }
        bodies.push_back(body);
    }
    for (const string kind : {"MRattle", "RigidSplitting", "MRattleLangevin"}) {
        vector<vector<Vec3> > results;
        for (const string threads : {"1", "2"}) {
            std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(kind, 0.002);
            if (auto* langevin = dynamic_cast<MRattleLangevinIntegrator*>(integrator.get()))
                langevin->setRandomNumberSeed(5);  // the same noise in both runs
            for (const vector<int>& body : bodies)
                integrator->addRigidBody(body);
            Context context(system, *integrator, platform("CPU"), {{"Threads", threads}});
            context.setPositions(positions);
            context.setVelocities(velocities);
            integrator->step(20);
            results.push_back(context.getState(State::Positions).getPositions());
        }
        EXPECT_GT(maxDeviation(positions, results[0]), 1e-3) << kind;  // they moved
        EXPECT_EQ(0.0, maxDeviation(results[0], results[1])) << kind;
        EXPECT_LT(maxDistanceChange(positions, results[1], bodies), 1e-10) << kind;
    }
}
