/*
 * MRattleDrudeNoseHooverIntegrator on Reference: bodies carrying Drude cores stay rigid;
 * kinetic + potential + both chains' energy is conserved up to the step's error; the bodies'
 * and the Drude particles' temperatures are their two targets within their statistical
 * errors; a checkpoint continues bit for bit; a failed step (a Drude particle beyond twice the
 * wall) leaves both chains as they were; bad settings are refused with a message; the settings
 * round-trip through XML. On the device platforms (OpenCL, CUDA): the step follows Reference's
 * (double precision), a failed step leaves both chains, the temperatures reach their targets
 * and checkpoints continue bit for bit.
 */
#include "DrudeTestSystem.h"
#include "MRattleDrudeLangevinIntegrator.h"
#include "MRattleDrudeNoseHooverIntegrator.h"
#include "MRattleIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "TestSupport.h"
#include "openmm/serialization/XmlSerializer.h"
#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

#ifdef MRATTLE_HAVE_DRUDE

using namespace MRattleTest::Drude;

namespace {

/** A State with its integrator parameters (both chains) as OpenMM's XML, to compare whole. */
string stateXml(Context& context) {
    const State state = context.getState(State::Positions | State::Velocities | State::IntegratorParameters);
    std::stringstream xml;
    XmlSerializer::serialize<State>(&state, "State", xml);
    return xml.str();
}

/**
 * A Context of the waters (no ions) for the integrator (on Reference unless named), at positions and velocities
 * from 3 ps of MRattleDrudeLangevinIntegrator at 300 K and Drude 50 K from the lattice: the
 * cluster's collapse heats it to about 1000 K, which Langevin takes out fast and a chain
 * slowly. The warm-up has the hard wall (0.02 nm): the Drude particles have no repulsion from
 * the waters' hydrogens, and a hot cluster brings on the polarization catastrophe, which only
 * the wall stops. (The free ions of drudeWaters() are no part of these runs, for that reason.)
 */
std::unique_ptr<Context> equilibratedWaters(const DrudeSystem& d, RigidBodyIntegrator& integrator,
                                            const string& platformName = "Reference") {
    MRattleDrudeLangevinIntegrator langevin(300, 5.0, 50, 20.0, 0.001);
    langevin.setRandomNumberSeed(3);
    langevin.setMaxDrudeDistance(0.02);   // the hot start's polarization catastrophe stopped, as in real SWM4-NDP runs
    std::unique_ptr<Context> warm = referenceContext(d, langevin);
    warm->setVelocitiesToTemperature(300, 3);
    langevin.step(3000);
    const State state = warm->getState(State::Positions | State::Velocities);
    std::unique_ptr<Context> context = platformContext(d, integrator, platformName);
    context->setPositions(state.getPositions());
    context->setVelocities(state.getVelocities());
    return context;
}

/**
 * Positions after 200 steps of 1 fs of each integrator from the same start (the first one's
 * draw: each integrator's setVelocitiesToTemperature() draws its own way), its bodies the
 * system's waters.
 */
vector<vector<Vec3> > runEach(const DrudeSystem& d, const vector<RigidBodyIntegrator*>& integrators) {
    vector<vector<Vec3> > positions;
    vector<Vec3> velocities;
    for (RigidBodyIntegrator* integrator : integrators) {
        std::unique_ptr<Context> context = referenceContext(d, *integrator);
        if (velocities.empty()) {
            context->setVelocitiesToTemperature(300, 4);
            velocities = context->getState(State::Velocities).getVelocities();
        }
        context->setVelocities(velocities);
        integrator->step(200);
        positions.push_back(context->getState(State::Positions).getPositions());
    }
    return positions;
}

void expectBitForBit(const vector<Vec3>& expected, const vector<Vec3>& actual) {
    for (size_t i = 0; i < expected.size(); i++)
        for (int k = 0; k < 3; k++)
            EXPECT_EQ(expected[i][k], actual[i][k]) << "particle " << i;
}

} // namespace

TEST(DrudeNoseHoover, BodiesStayRigidAndTheExtendedEnergyIsConserved) {
    // 8 waters without the wall (which is not Hamiltonian), 2000 steps of 0.5 fs: the chains
    // move energy in and out by tens of kJ/mol; kinetic + potential + bath moves by the
    // step's error only.
    DrudeSystem d = drudeWaters(8, 0, 0.34);
    MRattleDrudeNoseHooverIntegrator integrator(300, 10.0, 50.0, 20.0, 0.0005);
    integrator.setMaxDrudeDistance(0);
    std::unique_ptr<Context> context = equilibratedWaters(d, integrator);
    const State start = context->getState(State::Positions);
    vector<double> conserved, mechanical, bath;
    for (int k = 0; k < 200; k++) {
        integrator.step(10);
        const State state = context->getState(State::Energy);
        bath.push_back(integrator.computeHeatBathEnergy());
        mechanical.push_back(state.getKineticEnergy() + state.getPotentialEnergy());
        conserved.push_back(mechanical.back() + bath.back());
    }
    auto range = [](const vector<double>& x) {
        return *std::max_element(x.begin(), x.end()) - *std::min_element(x.begin(), x.end());
    };
    std::cout << "over 1 ps: kinetic + potential moves by " << range(mechanical) << " kJ/mol, the bath by "
              << range(bath) << ", their sum by " << range(conserved) << " (drift " << conserved.back() - conserved[0]
              << ")" << std::endl;
    EXPECT_GT(range(bath), 5.0);
    EXPECT_LT(range(conserved), 0.03 * range(mechanical));
    EXPECT_LT(std::fabs(conserved.back() - conserved[0]), 0.01 * range(mechanical));
    const State end = context->getState(State::Positions);
    double worst = 0;
    for (const vector<int>& body : d.bodies)
        for (size_t i = 0; i < body.size(); i++)
            for (size_t j = i + 1; j < body.size(); j++) {
                const double before = distance(start.getPositions()[body[i]], start.getPositions()[body[j]]);
                const double after = distance(end.getPositions()[body[i]], end.getPositions()[body[j]]);
                worst = std::max(worst, std::fabs(after - before));
            }
    EXPECT_LT(worst, 1e-10);
    EXPECT_EQ(8 * 6 + 8 * 3, integrator.getNumDegreesOfFreedom());
}

TEST(DrudeNoseHoover, BodyAndDrudeTemperaturesReachTheirTargets) {
    // 8 waters: 48 degrees of freedom at 300 K, 24 Drude ones at 50 K, with the wall (OpenMM's 0.02 nm).
    // Steps of 0.5 fs: at 1 fs (omega h about 1 for the Drude springs) the Drude temperature
    // read 49.3-51.9 K over four warm-up seeds, two of them more than 3 standard errors above 50.
    DrudeSystem d = drudeWaters(8, 0, 0.34);
    const double temperature = 300, drudeTemperature = 50;
    MRattleDrudeNoseHooverIntegrator integrator(temperature, 10.0, drudeTemperature, 20.0, 0.0005);
    std::unique_ptr<Context> context = equilibratedWaters(d, integrator);
    integrator.step(4000);
    vector<double> body, drude;
    for (int sample = 0; sample < 4000; sample++) {
        integrator.step(20);
        body.push_back(integrator.computeBodyTemperature());
        drude.push_back(integrator.computeDrudeTemperature());
    }
    const auto bodyMean = blockMean(body), drudeMean = blockMean(drude);
    std::cout << "body temperature " << bodyMean.first << " +- " << bodyMean.second << " K (target " << temperature
              << "), Drude temperature " << drudeMean.first << " +- " << drudeMean.second << " K (target "
              << drudeTemperature << ")" << std::endl;
    EXPECT_NEAR(temperature, bodyMean.first, 3 * bodyMean.second);
    EXPECT_NEAR(drudeTemperature, drudeMean.first, 3 * drudeMean.second);
    EXPECT_LT(bodyMean.second, 0.03 * temperature);
    EXPECT_LT(drudeMean.second, 0.03 * drudeTemperature);
}

TEST(DrudeNoseHoover, ACheckpointContinuesBitForBit) {
    // Both chains are in the checkpoint: 50 steps after loading it are the 50 steps run on.
    DrudeSystem d = drudeWaters(3, 1, 0.32);
    MRattleDrudeNoseHooverIntegrator integrator(300, 10.0, 50, 20.0, 0.001);
    std::unique_ptr<Context> context = referenceContext(d, integrator);
    context->setVelocitiesToTemperature(300, 6);
    integrator.step(20);
    std::stringstream checkpoint;
    context->createCheckpoint(checkpoint);
    const double bathAtCheckpoint = integrator.computeHeatBathEnergy();
    integrator.step(50);
    const string straight = stateXml(*context);
    const double bath = integrator.computeHeatBathEnergy();
    context->loadCheckpoint(checkpoint);
    EXPECT_EQ(bathAtCheckpoint, integrator.computeHeatBathEnergy());
    integrator.step(50);
    EXPECT_EQ(straight, stateXml(*context));
    EXPECT_EQ(bath, integrator.computeHeatBathEnergy());
    // The State names both chains' variables.
    for (const char* name : {"chainPositions", "chainVelocities", "drudeChainPositions", "drudeChainVelocities"})
        EXPECT_NE(string::npos, stateXml(*context).find(name)) << name;
}

TEST(DrudeNoseHoover, AFailedStepLeavesBothChainsAsBefore) {
    // After 30 steps both chains have moved; a Drude particle then sent off at 20 nm/ps
    // crosses twice a 0.004 nm wall in one 1 fs step: the step is refused, naming the
    // particle, and positions, velocities and both chains are as before it.
    DrudeSystem d = drudeWaters(2, 1, 0.4);
    MRattleDrudeNoseHooverIntegrator integrator(300, 10.0, 50, 20.0, 0.001);
    integrator.setMaxDrudeDistance(0.004);
    std::unique_ptr<Context> context = referenceContext(d, integrator);
    context->setVelocitiesToTemperature(300, 7);
    integrator.step(30);
    vector<Vec3> v = context->getState(State::Velocities).getVelocities();
    const int drude = d.pairs[0].first;
    v[drude] += Vec3(20.0, 0, 0);
    context->setVelocities(v);
    const string before = stateXml(*context);
    const double bath = integrator.computeHeatBathEnergy();
    const int steps = context->getState(0).getStepCount();
    const string message = messageOf([&] { integrator.step(1); });
    EXPECT_NE(string::npos, message.find("beyond twice the hard wall")) << message;
    EXPECT_NE(string::npos, message.find("Drude particle " + std::to_string(drude))) << message;
    EXPECT_NE(string::npos, message.find("MRattleDrudeNoseHooverIntegrator")) << message;
    EXPECT_EQ(before, stateXml(*context));
    EXPECT_EQ(bath, integrator.computeHeatBathEnergy());
    EXPECT_EQ(steps, context->getState(0).getStepCount());
    EXPECT_NE(0.0, bath);
}

TEST(DrudeNoseHoover, WithoutCouplingItIsMRattleIntegrator) {
    // Both frequencies 0 and no wall: the chains rest and the velocities are not touched,
    // so the step is MRattleIntegrator's velocity Verlet, bit for bit.
    DrudeSystem d = drudeWaters(3, 1, 0.32);
    MRattleIntegrator verlet(0.001);
    MRattleDrudeNoseHooverIntegrator drude(300, 0.0, 1.0, 0.0, 0.001);
    drude.setMaxDrudeDistance(0);
    const vector<vector<Vec3> > positions = runEach(d, {&verlet, &drude});
    expectBitForBit(positions[0], positions[1]);
}

TEST(DrudeNoseHoover, WithoutDrudeParticlesItIsMRattleNoseHoover) {
    // A System with no DrudeForce pair: the body chain sees all the kinetic energy and all
    // degrees of freedom, the Drude chain rests: MRattleNoseHooverIntegrator's step, bit for bit.
    DrudeSystem d = drudeWaters(3, 0, 0.32);
    for (int f = 0; f < d.system.getNumForces(); f++)
        if (auto* drude = dynamic_cast<DrudeForce*>(&d.system.getForce(f))) {
            d.system.removeForce(f);
            break;
        }
    d.system.addForce(new DrudeForce());   // present and empty
    // Without their springs the Drude particles would fall onto the other waters' charges: neutral here.
    NonbondedForce& nonbonded = dynamic_cast<NonbondedForce&>(d.system.getForce(0));
    for (const auto& pair : d.pairs) {
        double charge, sigma, epsilon;
        nonbonded.getParticleParameters(pair.first, charge, sigma, epsilon);
        nonbonded.setParticleParameters(pair.first, 0.0, sigma, epsilon);
    }
    for (int e = 0; e < nonbonded.getNumExceptions(); e++) {   // their repulsions' charges (the rest are 0 already)
        int i, j;
        double chargeProduct, sigma, epsilon;
        nonbonded.getExceptionParameters(e, i, j, chargeProduct, sigma, epsilon);
        nonbonded.setExceptionParameters(e, i, j, 0.0, sigma, epsilon);
    }
    MRattleNoseHooverIntegrator chain(300, 10.0, 0.001);
    MRattleDrudeNoseHooverIntegrator drude(300, 10.0, 1.0, 20.0, 0.001);
    const vector<vector<Vec3> > positions = runEach(d, {&chain, &drude});
    expectBitForBit(positions[0], positions[1]);
}

TEST(DrudeNoseHoover, ADrudeParticleInABodyIsRefusedNamingIt) {
    DrudeSystem d = drudeWaters(2, 0, 0.4);
    MRattleDrudeNoseHooverIntegrator integrator(300, 10.0, 1.0, 20.0, 0.001);
    integrator.addRigidBody({0, 1, 2});
    integrator.addRigidBody({4, 5, 6, 7});   // water 1 with its Drude particle 7
    const string message = messageOf([&] { Context context(d.system, integrator, platform("Reference")); });
    EXPECT_NE(string::npos, message.find("MRattleDrudeNoseHooverIntegrator")) << message;
    EXPECT_NE(string::npos, message.find("Drude particle 7")) << message;
}

TEST(DrudeNoseHoover, OnDevicesItFollowsReferenceAndAFailedStepLeavesBothChains) {
    // Double precision, both chains coupled and a wall at 0.002 nm that the Drude particles
    // reach often: 200 steps of 0.25 fs from the same state follow Reference's, chains and
    // bounces (without the wall Reference ends far from both). Then a Drude particle sent off
    // at 40 nm/ps (0.01 nm in a step, from at most 0.002 nm off its core) crosses twice the wall: the step is refused, and positions, velocities and
    // both chains are as before it.
    bool any = false;
    for (const string& name : devicePlatforms()) {
        if (!unavailable(name).empty())
            continue;
        any = true;
        DrudeSystem d = drudeWaters(2, 1, 0.4);
        const double wall = 0.002;
        vector<vector<Vec3> > positions;
        vector<double> baths;
        std::unique_ptr<Context> device;
        MRattleDrudeNoseHooverIntegrator withoutWall(300, 10.0, 50, 20.0, 0.00025), onReference(300, 10.0, 50, 20.0, 0.00025),
            onDevice(300, 10.0, 50, 20.0, 0.00025);
        vector<Vec3> velocities;
        for (MRattleDrudeNoseHooverIntegrator* integrator : {&withoutWall, &onReference, &onDevice}) {
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
            baths.push_back(integrator->computeHeatBathEnergy());
            if (integrator == &onDevice)
                device = std::move(context);
        }
        const double deviation = maxDeviation(positions[1], positions[2]);
        std::cout << name << ": after 200 steps " << deviation << " nm from Reference, heat bath " << baths[2]
                  << " kJ/mol (Reference's " << baths[1] << ", relative difference "
                  << std::fabs(baths[2] - baths[1]) / std::fabs(baths[1]) << "); Reference without the wall "
                  << maxDeviation(positions[0], positions[1]) << " nm away" << std::endl;
        EXPECT_LT(deviation, 1e-7) << name;
        EXPECT_NEAR(baths[1], baths[2], 1e-6 * std::fabs(baths[1])) << name;
        EXPECT_GT(std::fabs(baths[1]), 0.1) << name;   // the chains moved
        EXPECT_GT(maxDeviation(positions[0], positions[2]), 1e-4) << name;   // the wall acted
        vector<Vec3> v = device->getState(State::Velocities).getVelocities();
        const int drude = d.pairs[0].first;
        v[drude] += Vec3(40.0, 0, 0);
        device->setVelocities(v);
        const string before = stateXml(*device);
        const double bath = onDevice.computeHeatBathEnergy();
        const int steps = device->getState(0).getStepCount();
        const string message = messageOf([&] { onDevice.step(1); });
        EXPECT_NE(string::npos, message.find("beyond twice the hard wall")) << message;
        EXPECT_NE(string::npos, message.find("MRattleDrudeNoseHooverIntegrator")) << message;
        EXPECT_EQ(before, stateXml(*device)) << name;
        EXPECT_EQ(bath, onDevice.computeHeatBathEnergy()) << name;
        EXPECT_EQ(steps, device->getState(0).getStepCount()) << name;
    }
    // A build or machine without OpenCL/CUDA (no pocl, no GPU): said, not passed.
    if (!any)
        GTEST_SKIP() << "no device platform here";
}

TEST(DrudeNoseHoover, OnDevicesTheTemperaturesReachTheirTargetsAndACheckpointContinuesBitForBit) {
    // The device's default (single) precision on the Reference test's system and targets:
    // 48 body degrees of freedom at 300 K, 24 Drude ones at 50 K, with the wall (0.02 nm);
    // then 50 steps after loading a checkpoint are the 50 steps run on, both chains included.
    bool any = false;
    for (const string& name : devicePlatforms()) {
        if (!unavailable(name).empty())
            continue;
        any = true;
        DrudeSystem d = drudeWaters(8, 0, 0.34);
        const double temperature = 300, drudeTemperature = 50;
        MRattleDrudeNoseHooverIntegrator integrator(temperature, 10.0, drudeTemperature, 20.0, 0.0005);   // as on Reference
        std::unique_ptr<Context> context = equilibratedWaters(d, integrator, name);
        integrator.step(4000);
        vector<double> body, drude;
        for (int sample = 0; sample < 4000; sample++) {
            integrator.step(20);
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
        const string straight = stateXml(*context);
        context->loadCheckpoint(checkpoint);
        integrator.step(50);
        EXPECT_EQ(straight, stateXml(*context)) << name;
    }
    if (!any)
        GTEST_SKIP() << "no device platform here";
}

#endif // MRATTLE_HAVE_DRUDE

TEST(DrudeNoseHoover, BadSettingsAreRefused) {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    for (double bad : {-1.0, nan, inf}) {
        EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(bad, 10.0, 1.0, 20.0, 0.001), OpenMMException);
        EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(300, bad, 1.0, 20.0, 0.001), OpenMMException);
        EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, bad, 20.0, 0.001), OpenMMException);
        EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, 1.0, bad, 0.001), OpenMMException);
        MRattleDrudeNoseHooverIntegrator integrator(300, 10.0, 1.0, 20.0, 0.001);
        EXPECT_THROW(integrator.setMaxDrudeDistance(bad), OpenMMException);
        EXPECT_THROW(integrator.setDrudeTemperature(bad), OpenMMException);
        EXPECT_THROW(integrator.setDrudeCollisionFrequency(bad), OpenMMException);
        EXPECT_EQ(0.02, integrator.getMaxDrudeDistance());   // OpenMM's default, unchanged by a refused setting
        EXPECT_EQ(1.0, integrator.getDrudeTemperature());
    }
    // The chains' masses are proportional to the temperatures: 0 K is refused for both.
    EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(0.0, 10.0, 1.0, 20.0, 0.001), OpenMMException);
    EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, 0.0, 20.0, 0.001), OpenMMException);
    EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, 1.0, 20.0, 0.001, 0), OpenMMException);
    EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, 1.0, 20.0, 0.001, 3, 0), OpenMMException);
    for (int order : {0, 2, 4, 9})
        EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, 1.0, 20.0, 0.001, 3, 3, order), OpenMMException);
    for (int order : {1, 3, 5, 7})
        EXPECT_NO_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, 1.0, 20.0, 0.001, 3, 3, order));
    const string message = messageOf([] { MRattleDrudeNoseHooverIntegrator(300, 10.0, -1.0, 20.0, 0.001); });
    EXPECT_NE(string::npos, message.find("MRattleDrudeNoseHooverIntegrator")) << message;
    EXPECT_NE(string::npos, message.find("Drude temperature")) << message;
    MRattleDrudeNoseHooverIntegrator unbound(300, 10.0, 1.0, 20.0, 0.001);
    EXPECT_THROW(unbound.computeHeatBathEnergy(), OpenMMException);
}

TEST(DrudeNoseHoover, SettingsRoundTripThroughXml) {
    MRattleDrudeNoseHooverIntegrator integrator(310, 2.0, 1.5, 25.0, 0.0015, 4, 2, 5);
    integrator.setMaxDrudeDistance(0.03);
    std::unique_ptr<Integrator> copy = fromXml(toXml(integrator));
    auto& read = dynamic_cast<MRattleDrudeNoseHooverIntegrator&>(*copy);
    EXPECT_EQ(310, read.getTemperature());
    EXPECT_EQ(2.0, read.getCollisionFrequency());
    EXPECT_EQ(1.5, read.getDrudeTemperature());
    EXPECT_EQ(25.0, read.getDrudeCollisionFrequency());
    EXPECT_EQ(0.03, read.getMaxDrudeDistance());
    EXPECT_EQ(4, read.getChainLength());
    EXPECT_EQ(2, read.getNumMultiTimeSteps());
    EXPECT_EQ(5, read.getNumYoshidaSuzukiTimeSteps());
    EXPECT_EQ(0.0015, read.getStepSize());
}
