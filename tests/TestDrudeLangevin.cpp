/*
 * MRattleDrudeLangevinIntegrator on Reference: bodies carrying Drude cores stay rigid and a
 * free Drude pair moves; the bodies' and the Drude particles' temperatures are their two
 * targets within their statistical errors; a Drude particle in a body and bad settings are
 * refused with a message; the hard wall holds Drude particles near their cores and a step that
 * crosses twice it is refused; checkpoints continue bit for bit; the Drude noise alone keeps
 * momentum; the settings round-trip through XML. On the device platforms (OpenCL, CUDA): the
 * deterministic step (no friction, with the wall) follows Reference's, a failed step is undone,
 * the temperatures reach their targets and checkpoints continue bit for bit.
 */
#include "MRattleDrudeLangevinIntegrator.h"
#include "MRattleLangevinIntegrator.h"
#include "DrudeTestSystem.h"
#include "TestSupport.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <gtest/gtest.h>
#include <cmath>
#include <limits>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

#ifdef MRATTLE_HAVE_DRUDE

using namespace MRattleTest::Drude;

TEST(DrudeLangevin, BodiesWithDrudeCoresStayRigidAndFreePairsMove) {
    DrudeSystem d = drudeWaters(4, 1, 0.32);
    MRattleDrudeLangevinIntegrator integrator(300, 5.0, 1.0, 20.0, 0.001);
    integrator.setRandomNumberSeed(11);
    std::unique_ptr<Context> context = referenceContext(d, integrator);
    context->setVelocitiesToTemperature(300, 5);
    const State start = context->getState(State::Positions);
    integrator.step(2000);
    const State end = context->getState(State::Positions | State::Velocities);
    double worst = 0;
    for (const vector<int>& body : d.bodies)
        for (size_t i = 0; i < body.size(); i++)
            for (size_t j = i + 1; j < body.size(); j++) {
                const double before = distance(start.getPositions()[body[i]], start.getPositions()[body[j]]);
                const double after = distance(end.getPositions()[body[i]], end.getPositions()[body[j]]);
                worst = std::max(worst, std::fabs(after - before));
            }
    EXPECT_LT(worst, 1e-10);
    // The Drude particles move relative to their cores (they are not held), and stay near them.
    for (const auto& pair : d.pairs) {
        const double separation = distance(end.getPositions()[pair.first], end.getPositions()[pair.second]);
        EXPECT_GT(separation, 0.0) << "Drude particle " << pair.first;
        EXPECT_LT(separation, 0.02) << "Drude particle " << pair.first;
    }
    // The free pair's core moved (it is free, not frozen).
    const int ion = d.pairs.back().second;
    EXPECT_GT(distance(start.getPositions()[ion], end.getPositions()[ion]), 1e-3);
    // Degrees of freedom: 6 per water, 3 per Drude particle, 3 for the ion's core.
    EXPECT_EQ(4 * 6 + 5 * 3 + 3, integrator.getNumDegreesOfFreedom());
}

TEST(DrudeLangevin, BodyAndDrudeTemperaturesReachTheirTargets) {
    // 8 waters and 2 ions: 51 degrees of freedom at 300 K, 30 Drude ones at 50 K.
    DrudeSystem d = drudeWaters(8, 2, 0.34);
    const double temperature = 300, drudeTemperature = 50;
    MRattleDrudeLangevinIntegrator integrator(temperature, 5.0, drudeTemperature, 20.0, 0.001);
    integrator.setRandomNumberSeed(2024);
    // The hard wall of real SWM4-NDP runs (0.02 nm, 10 times the Drude particles' thermal
    // reach at 50 K): these Drude particles have no repulsion, and without it a hot start may
    // bring on the polarization catastrophe.
    integrator.setMaxDrudeDistance(0.02);
    std::unique_ptr<Context> context = referenceContext(d, integrator);
    context->setVelocitiesToTemperature(temperature, 3);
    integrator.step(2000);
    vector<double> body, drude;
    for (int sample = 0; sample < 4000; sample++) {
        integrator.step(10);
        body.push_back(integrator.computeBodyTemperature());
        drude.push_back(integrator.computeDrudeTemperature());
    }
    const auto bodyMean = blockMean(body), drudeMean = blockMean(drude);
    std::cout << "body temperature " << bodyMean.first << " +- " << bodyMean.second << " K (target " << temperature
              << "), Drude temperature " << drudeMean.first << " +- " << drudeMean.second << " K (target "
              << drudeTemperature << ")" << std::endl;
    EXPECT_NEAR(temperature, bodyMean.first, 3 * bodyMean.second);
    EXPECT_NEAR(drudeTemperature, drudeMean.first, 3 * drudeMean.second);
    // Errors small enough for the check to mean something (a few per cent).
    EXPECT_LT(bodyMean.second, 0.03 * temperature);
    EXPECT_LT(drudeMean.second, 0.03 * drudeTemperature);
}

TEST(DrudeLangevin, DrudeNoiseAloneKeepsMomentumAndAngularMomentum) {
    // Without friction on the bodies only C is thermostatted: its noise and friction move
    // each augmented body's Drude particles with zero momentum and zero angular momentum,
    // and the forces (vacuum, no cutoff) and M-RATTLE keep both, so the totals stay as they
    // began. (A free pair's C is its relative motion, which turns the pair: no ions here.)
    // On Reference and, in double precision, on each device platform.
    vector<string> platforms = {"Reference"};
    for (const string& name : devicePlatforms())
        if (unavailable(name).empty())
            platforms.push_back(name);
    for (const string& name : platforms) {
        DrudeSystem d = drudeWaters(4, 0, 0.32);
        MRattleDrudeLangevinIntegrator integrator(300, 0.0, 50, 20.0, 0.001);
        integrator.setRandomNumberSeed(9);
        std::unique_ptr<Context> context = platformContext(d, integrator, name, platformProperties(name));
        context->setVelocitiesToTemperature(300, 8);
        const vector<double> m = masses(d.system);
        const State start = context->getState(State::Positions | State::Velocities);
        integrator.step(1000);
        const State end = context->getState(State::Positions | State::Velocities);
        const Vec3 p0 = totalMomentum(m, start.getVelocities()), p1 = totalMomentum(m, end.getVelocities());
        // Leapfrog keeps sum m x_n x v_{n-1/2} (each drift moves x along v; the kicks are central,
        // the noise has none about the positions it is drawn at, those the last half drift leaves
        // it parallel to): the State's positions and velocities as they are.
        const Vec3 l0 = angularMomentum(m, start.getPositions(), start.getVelocities());
        const Vec3 l1 = angularMomentum(m, end.getPositions(), end.getVelocities());
        for (int k = 0; k < 3; k++) {
            EXPECT_NEAR(p0[k], p1[k], 1e-9) << name << ", momentum, axis " << k;
            EXPECT_NEAR(l0[k], l1[k], 1e-6) << name << ", angular momentum, axis " << k;
        }
        // The Drude particles did get the noise: they are near 50 K, not at the start's 300 K.
        EXPECT_LT(integrator.computeDrudeTemperature(), 150) << name;
    }
}

TEST(DrudeLangevin, WithoutFrictionItIsMRattleLangevin) {
    // Both frictions 0: no noise, one drift, no wall: MRattleLangevinIntegrator's step at zero friction, bit for bit.
    // One draw for both (each integrator's setVelocitiesToTemperature() draws its own way).
    DrudeSystem d = drudeWaters(3, 1, 0.32);
    vector<vector<Vec3> > positions;
    vector<Vec3> velocities;
    for (int kind = 0; kind < 2; kind++) {
        std::unique_ptr<RigidBodyIntegrator> integrator;
        if (kind == 0)
            integrator.reset(new MRattleLangevinIntegrator(300, 0.0, 0.001));
        else
            integrator.reset(new MRattleDrudeLangevinIntegrator(300, 0.0, 1.0, 0.0, 0.001));
        for (const vector<int>& body : d.bodies)
            integrator->addRigidBody(body);
        Context context(d.system, *integrator, platform("Reference"));
        context.setPositions(d.positions);
        if (velocities.empty()) {
            context.setVelocitiesToTemperature(300, 4);
            velocities = context.getState(State::Velocities).getVelocities();
        }
        context.setVelocities(velocities);
        integrator->step(200);
        positions.push_back(context.getState(State::Positions).getPositions());
    }
    for (size_t i = 0; i < positions[0].size(); i++)
        for (int k = 0; k < 3; k++)
            EXPECT_EQ(positions[0][i][k], positions[1][i][k]) << "particle " << i;
}

TEST(DrudeLangevin, ACheckpointContinuesBitForBit) {
    // The random stream is in the checkpoint: 50 steps after loading it are the 50 steps run on.
    DrudeSystem d = drudeWaters(3, 1, 0.32);
    MRattleDrudeLangevinIntegrator integrator(300, 5.0, 50, 20.0, 0.001);
    integrator.setRandomNumberSeed(21);
    std::unique_ptr<Context> context = referenceContext(d, integrator);
    context->setVelocitiesToTemperature(300, 6);
    integrator.step(20);
    std::stringstream checkpoint;
    context->createCheckpoint(checkpoint);
    integrator.step(50);
    const vector<Vec3> straight = context->getState(State::Positions).getPositions();
    context->loadCheckpoint(checkpoint);
    integrator.step(50);
    const vector<Vec3> again = context->getState(State::Positions).getPositions();
    for (size_t i = 0; i < straight.size(); i++)
        for (int k = 0; k < 3; k++)
            EXPECT_EQ(straight[i][k], again[i][k]) << "particle " << i;
}

TEST(DrudeLangevin, ADrudeParticleInABodyIsRefusedNamingIt) {
    DrudeSystem d = drudeWaters(2, 0, 0.4);
    MRattleDrudeLangevinIntegrator integrator(300, 1.0, 1.0, 20.0, 0.001);
    integrator.addRigidBody({0, 1, 2});
    integrator.addRigidBody({4, 5, 6, 7});   // water 1 with its Drude particle 7
    const string message = messageOf([&] { Context context(d.system, integrator, platform("Reference")); });
    EXPECT_NE(string::npos, message.find("MRattleDrudeLangevinIntegrator")) << message;
    EXPECT_NE(string::npos, message.find("Drude particle 7")) << message;
    // Bodies left to the molecules take the Drude particles in (DrudeForce bonds them): refused too.
    MRattleDrudeLangevinIntegrator byMolecules(300, 1.0, 1.0, 20.0, 0.001);
    const string byMoleculesMessage = messageOf([&] { Context context(d.system, byMolecules, platform("Reference")); });
    EXPECT_NE(string::npos, byMoleculesMessage.find("Drude particle 3")) << byMoleculesMessage;
    EXPECT_NE(string::npos, byMoleculesMessage.find("addRigidBody")) << byMoleculesMessage;
}

TEST(DrudeLangevin, AMasslessCoreIsRefused) {
    DrudeSystem d = drudeWaters(0, 1, 0.4);
    d.system.setParticleMass(0, 0.0);
    MRattleDrudeLangevinIntegrator integrator(300, 1.0, 1.0, 20.0, 0.001);
    const string message = messageOf([&] { Context context(d.system, integrator, platform("Reference")); });
    EXPECT_NE(string::npos, message.find("without mass")) << message;
}

TEST(DrudeLangevin, HardWallKeepsDrudeParticlesNearTheirCores) {
    // Drude particles at 300 K are about 0.004 nm from their cores (sqrt(3 kT / k)): a wall
    // at 0.005 nm is reached, and holds them within it at every step's end, the cores in
    // bodies and the free one alike. A short step (omega h = 0.25) keeps a step's motion
    // well inside twice the wall, where the step would fail.
    DrudeSystem d = drudeWaters(2, 1, 0.4);
    MRattleDrudeLangevinIntegrator integrator(300, 5.0, 300, 20.0, 0.00025);
    const double wall = 0.005;
    integrator.setMaxDrudeDistance(wall);
    integrator.setRandomNumberSeed(5);
    std::unique_ptr<Context> context = referenceContext(d, integrator);
    const State start = context->getState(State::Positions);
    double farthest = 0;
    for (int k = 0; k < 1000; k++) {
        integrator.step(5);
        const State state = context->getState(State::Positions);
        for (const auto& pair : d.pairs)
            farthest = std::max(farthest, distance(state.getPositions()[pair.first], state.getPositions()[pair.second]));
        // The bodies stay rigid through the bounces.
        for (const vector<int>& body : d.bodies)
            EXPECT_NEAR(distance(start.getPositions()[body[0]], start.getPositions()[body[1]]),
                        distance(state.getPositions()[body[0]], state.getPositions()[body[1]]), 1e-10);
    }
    EXPECT_LE(farthest, wall * (1 + 1e-9));
    EXPECT_GT(farthest, 0.9 * wall);
}

TEST(DrudeLangevin, ADrudeParticleBeyondTwiceTheWallFailsTheStep) {
    // Hot Drude particles (3000 K) with a 1 fs step cross twice a 0.004 nm wall in one step:
    // that step is refused, naming the particle, with the state as before it.
    DrudeSystem d = drudeWaters(2, 1, 0.4);
    MRattleDrudeLangevinIntegrator integrator(300, 5.0, 3000, 20.0, 0.001);
    integrator.setMaxDrudeDistance(0.004);
    integrator.setRandomNumberSeed(5);
    std::unique_ptr<Context> context = referenceContext(d, integrator);
    string message;
    State before = context->getState(State::Positions);
    for (int k = 0; k < 100 && message.empty(); k++) {
        before = context->getState(State::Positions);
        try {
            integrator.step(1);
        } catch (const OpenMMException& e) {
            message = e.what();
        }
    }
    EXPECT_NE(string::npos, message.find("beyond twice the hard wall")) << message;
    EXPECT_NE(string::npos, message.find("MRattleDrudeLangevinIntegrator")) << message;
    const State after = context->getState(State::Positions);
    EXPECT_EQ(before.getStepCount(), after.getStepCount());
    for (size_t i = 0; i < d.positions.size(); i++)
        EXPECT_EQ(before.getPositions()[i][0], after.getPositions()[i][0]) << "particle " << i;
}

TEST(DrudeLangevin, OnDevicesWithoutFrictionItFollowsReferenceAndAFailedStepIsUndone) {
    // Double precision, both frictions 0 (deterministic) and a wall at 0.002 nm that the Drude
    // particles (0.004 nm at 300 K) reach often: 200 steps of 0.25 fs from the same state
    // follow Reference's bounces (without the wall Reference ends far from both). Then a Drude
    // particle sent off at 40 nm/ps (0.01 nm in a step, from at most 0.002 nm off its core) crosses twice the wall: the step is refused, and the
    // Context holds the state from before it.
    bool any = false;
    for (const string& name : devicePlatforms()) {
        if (!unavailable(name).empty())
            continue;
        any = true;
        DrudeSystem d = drudeWaters(2, 1, 0.4);
        const double wall = 0.002;
        vector<vector<Vec3> > positions;
        std::unique_ptr<Context> device;
        MRattleDrudeLangevinIntegrator withoutWall(300, 0.0, 300, 0.0, 0.00025), onReference(300, 0.0, 300, 0.0, 0.00025),
            onDevice(300, 0.0, 300, 0.0, 0.00025);
        vector<Vec3> velocities;
        for (MRattleDrudeLangevinIntegrator* integrator : {&withoutWall, &onReference, &onDevice}) {
            integrator->setMaxDrudeDistance(integrator == &withoutWall ? 0.0 : wall);
            std::unique_ptr<Context> context = (integrator != &onDevice ? referenceContext(d, *integrator)
                                                : platformContext(d, *integrator, name, {{"Precision", "double"}}));
            if (velocities.empty()) {
                context->setVelocitiesToTemperature(300, 5);
                velocities = context->getState(State::Velocities).getVelocities();
            }
            context->setVelocities(velocities);
            integrator->step(200);
            positions.push_back(context->getState(State::Positions).getPositions());
            if (integrator == &onDevice)
                device = std::move(context);
        }
        const double deviation = maxDeviation(positions[1], positions[2]);
        std::cout << name << ": after 200 steps " << deviation << " nm from Reference; Reference without the wall "
                  << maxDeviation(positions[0], positions[1]) << " nm away" << std::endl;
        EXPECT_LT(deviation, 1e-7) << name;
        EXPECT_GT(maxDeviation(positions[0], positions[2]), 1e-4) << name;   // the wall acted
        EXPECT_LE(farthestDrude(d, positions[2]), wall * (1 + 1e-9)) << name;
        vector<Vec3> v = device->getState(State::Velocities).getVelocities();
        v[d.pairs[0].first] += Vec3(40.0, 0, 0);
        device->setVelocities(v);
        const State before = device->getState(State::Positions | State::Velocities);
        const string message = messageOf([&] { onDevice.step(1); });
        EXPECT_NE(string::npos, message.find("beyond twice the hard wall")) << message;
        EXPECT_NE(string::npos, message.find("MRattleDrudeLangevinIntegrator")) << message;
        const State after = device->getState(State::Positions | State::Velocities);
        EXPECT_EQ(before.getStepCount(), after.getStepCount());
        for (size_t i = 0; i < d.positions.size(); i++)
            for (int k = 0; k < 3; k++) {
                EXPECT_EQ(before.getPositions()[i][k], after.getPositions()[i][k]) << "particle " << i;
                EXPECT_EQ(before.getVelocities()[i][k], after.getVelocities()[i][k]) << "particle " << i;
            }
    }
    // A build or machine without OpenCL/CUDA (no pocl, no GPU): said, not passed.
    if (!any)
        GTEST_SKIP() << "no device platform here";
}

TEST(DrudeLangevin, OnDevicesTheTemperaturesReachTheirTargetsAndACheckpointContinuesBitForBit) {
    // The device's default (single) precision on the Reference test's system and targets: the
    // bodies at 300 K and the Drude particles at 50 K within their statistical errors; then 50
    // steps after loading a checkpoint are the 50 steps run on (OpenMM's device random numbers
    // are in it).
    bool any = false;
    for (const string& name : devicePlatforms()) {
        if (!unavailable(name).empty())
            continue;
        any = true;
        DrudeSystem d = drudeWaters(8, 2, 0.34);
        const double temperature = 300, drudeTemperature = 50;
        MRattleDrudeLangevinIntegrator integrator(temperature, 5.0, drudeTemperature, 20.0, 0.001);
        integrator.setRandomNumberSeed(2024);
        integrator.setMaxDrudeDistance(0.02);   // as on Reference
        std::unique_ptr<Context> context = platformContext(d, integrator, name);
        context->setVelocitiesToTemperature(temperature, 3);
        integrator.step(2000);
        vector<double> body, drude;
        for (int sample = 0; sample < 4000; sample++) {
            integrator.step(10);
            body.push_back(integrator.computeBodyTemperature());
            drude.push_back(integrator.computeDrudeTemperature());
        }
        const auto bodyMean = blockMean(body), drudeMean = blockMean(drude);
        std::cout << name << ": body temperature " << bodyMean.first << " +- " << bodyMean.second << " K (target "
                  << temperature << "), Drude temperature " << drudeMean.first << " +- " << drudeMean.second
                  << " K (target " << drudeTemperature << ")" << std::endl;
        EXPECT_NEAR(temperature, bodyMean.first, 3 * bodyMean.second) << name;
        EXPECT_NEAR(drudeTemperature, drudeMean.first, 3 * drudeMean.second) << name;
        EXPECT_LT(bodyMean.second, 0.03 * temperature) << name;
        EXPECT_LT(drudeMean.second, 0.03 * drudeTemperature) << name;
        std::stringstream checkpoint;
        context->createCheckpoint(checkpoint);
        integrator.step(50);
        const vector<Vec3> straight = context->getState(State::Positions).getPositions();
        context->loadCheckpoint(checkpoint);
        integrator.step(50);
        const vector<Vec3> again = context->getState(State::Positions).getPositions();
        for (size_t i = 0; i < straight.size(); i++)
            for (int k = 0; k < 3; k++)
                EXPECT_EQ(straight[i][k], again[i][k]) << name << ", particle " << i;
    }
    if (!any)
        GTEST_SKIP() << "no device platform here";
}

#endif // MRATTLE_HAVE_DRUDE

TEST(DrudeLangevin, BadSettingsAreRefused) {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    for (double bad : {-1.0, nan, inf}) {
        EXPECT_THROW(MRattleDrudeLangevinIntegrator(bad, 1.0, 1.0, 20.0, 0.001), OpenMMException);
        EXPECT_THROW(MRattleDrudeLangevinIntegrator(300, bad, 1.0, 20.0, 0.001), OpenMMException);
        EXPECT_THROW(MRattleDrudeLangevinIntegrator(300, 1.0, bad, 20.0, 0.001), OpenMMException);
        EXPECT_THROW(MRattleDrudeLangevinIntegrator(300, 1.0, 1.0, bad, 0.001), OpenMMException);
        MRattleDrudeLangevinIntegrator integrator(300, 1.0, 1.0, 20.0, 0.001);
        EXPECT_THROW(integrator.setMaxDrudeDistance(bad), OpenMMException);
        EXPECT_THROW(integrator.setDrudeTemperature(bad), OpenMMException);
        EXPECT_THROW(integrator.setDrudeFriction(bad), OpenMMException);
        EXPECT_EQ(0.0, integrator.getMaxDrudeDistance());   // unchanged by a refused setting
    }
    const string message = messageOf([] { MRattleDrudeLangevinIntegrator(300, 1.0, -1.0, 20.0, 0.001); });
    EXPECT_NE(string::npos, message.find("MRattleDrudeLangevinIntegrator")) << message;
    EXPECT_NE(string::npos, message.find("Drude temperature")) << message;
}

TEST(DrudeLangevin, SettingsRoundTripThroughXml) {
    MRattleDrudeLangevinIntegrator integrator(310, 2.0, 1.5, 25.0, 0.0015);
    integrator.setMaxDrudeDistance(0.02);
    integrator.setRandomNumberSeed(17);
    std::unique_ptr<Integrator> copy = fromXml(toXml(integrator));
    auto& read = dynamic_cast<MRattleDrudeLangevinIntegrator&>(*copy);
    EXPECT_EQ(310, read.getTemperature());
    EXPECT_EQ(2.0, read.getFriction());
    EXPECT_EQ(1.5, read.getDrudeTemperature());
    EXPECT_EQ(25.0, read.getDrudeFriction());
    EXPECT_EQ(0.02, read.getMaxDrudeDistance());
    EXPECT_EQ(17, read.getRandomNumberSeed());
    EXPECT_EQ(0.0015, read.getStepSize());
}
