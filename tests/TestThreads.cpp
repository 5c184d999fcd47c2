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
#include <algorithm>
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
    for (const IntegratorTraits& traits : integrators()) {
        const string& kind = traits.name;
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

TEST(Threads, TheFirstFailingBodyIsReportedWhicheverThreadHasIt) {
    // 1024 benzenes at rest but for fast spinners, which a 0.1 ps step turns by 2 rad: their
    // position reset fails. With 3 threads the bodies are split in thirds, the last third on
    // the calling thread. The error names the lowest failing body and the step is undone.
    Molecule b = benzene();
    const int numBodies = 1024;
    for (const vector<int> spinners : {vector<int>{900}, vector<int>{500, 900}, vector<int>{100, 500}}) {
        System system;
        vector<Vec3> positions, velocities;
        std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator("MRattle", 0.1);
        for (int body = 0; body < numBodies; body++) {
            const bool spins = std::find(spinners.begin(), spinners.end(), body) != spinners.end();
            vector<int> atoms;
            for (size_t i = 0; i < b.sites.size(); i++) {
                atoms.push_back(system.addParticle(b.masses[i]));
                positions.push_back(b.sites[i] + Vec3(0.8 * (body % 32), 0.8 * (body / 32), 0));
                velocities.push_back(spins ? Vec3(0, 0, 20).cross(b.sites[i]) : Vec3());
            }
            integrator->addRigidBody(atoms);
        }
        Context context(system, *integrator, platform("CPU"), {{"Threads", "3"}});
        context.setPositions(positions);
        context.setVelocities(velocities);
        const string message = messageOf([&] { integrator->step(1); });
        EXPECT_NE(string::npos, message.find("rigid body " + std::to_string(spinners[0]) + " ")) << message;
        State state = context.getState(State::Positions);
        EXPECT_EQ(0, state.getStepCount());
        EXPECT_EQ(0.0, maxDeviation(positions, state.getPositions()));
    }
}
