/*
 * Both Drude integrators (MRattleDrudeLangevinIntegrator, MRattleDrudeNoseHooverIntegrator),
 * one suite; what only one of them promises is guarded by its kind.
 *
 * On every platform that runs them (DrudeIntegrators): setVelocitiesToTemperature() draws the
 * bodies at the temperature and the Drude particles' relative motion at the Drude temperature;
 * a DrudeForce added to the System (or given more pairs) after the Context was created makes
 * the next step fail naming the integrator, with positions and velocities as they were, until
 * Context::reinitialize(); the bodies' and the Drude particles' temperatures reach their two
 * targets within their statistical errors (the Drude one also within 2%, the test system's
 * steady-state excess) and a checkpoint continues bit for bit (both chains
 * with it); a Drude particle beyond twice the hard wall fails the step, which leaves the State
 * (and both chains) as before it, and on a device platform (double precision) the walled step
 * follows Reference's first; the Drude temperature is the Drude particles' motion relative
 * to their cores (none when they move with them, the bodies turning); Langevin: its Drude
 * noise alone keeps momentum, and a strong Drude friction leaves the Drude particles moving
 * with their cores.
 *
 * On Reference (DrudeOnReference): bodies carrying Drude cores stay rigid (Langevin: a free
 * Drude pair moves; Nose-Hoover: kinetic + potential + both chains' energy is conserved); with
 * both couplings off each is its plain counterpart bit for bit (Nose-Hoover also without Drude
 * particles); a Drude particle in a body and a massless core are refused with a message;
 * Langevin: the hard wall holds the Drude particles and a hot Drude particle crossing twice it
 * fails the step. Without OpenMM's Drude plugin too (DrudeSettings): bad settings are refused
 * with a message and the settings round-trip through XML. On each device platform
 * (DrudeReordering): a periodic system with a cutoff, whose atoms the device reorders, follows
 * Reference through the reorderings.
 */
#include "DrudeTestSystem.h"
#include "TestSupport.h"
#include "MRattleDrudeLangevinIntegrator.h"
#include "MRattleDrudeNoseHooverIntegrator.h"
#include "MRattleIntegrator.h"
#include "MRattleLangevinIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include "openmm/serialization/XmlSerializer.h"
#include <gtest/gtest.h>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

const string langevinKind = "MRattleDrudeLangevin", noseHooverKind = "MRattleDrudeNoseHoover";

bool isLangevin(const string& kind) {
    return kind == langevinKind;
}

/**
 * One of the two Drude integrators, seen through what both have: the couplings are Langevin's
 * frictions or Nose-Hoover's collision frequencies.
 */
class DrudeView {
public:
    explicit DrudeView(RigidBodyIntegrator& integrator)
        : langevin(dynamic_cast<MRattleDrudeLangevinIntegrator*>(&integrator)),
          noseHoover(dynamic_cast<MRattleDrudeNoseHooverIntegrator*>(&integrator)) {
        if (!langevin && !noseHoover)
            throw OpenMMException("not a Drude integrator");
    }
    /** OpenMM's Drude integrators' arguments, in their order. */
    static std::unique_ptr<RigidBodyIntegrator> make(const string& kind, double temperature, double coupling,
                                                     double drudeTemperature, double drudeCoupling, double stepSize) {
        if (kind == langevinKind)
            return std::unique_ptr<RigidBodyIntegrator>(
                new MRattleDrudeLangevinIntegrator(temperature, coupling, drudeTemperature, drudeCoupling, stepSize));
        return std::unique_ptr<RigidBodyIntegrator>(
            new MRattleDrudeNoseHooverIntegrator(temperature, coupling, drudeTemperature, drudeCoupling, stepSize));
    }
    bool isLangevin() const {
        return langevin != nullptr;
    }
    /** "MRattleDrudeLangevinIntegrator" or "MRattleDrudeNoseHooverIntegrator": what messages name. */
    string className() const {
        return langevin ? "MRattleDrudeLangevinIntegrator" : "MRattleDrudeNoseHooverIntegrator";
    }
    double computeDrudeTemperature() const {
        return langevin ? langevin->computeDrudeTemperature() : noseHoover->computeDrudeTemperature();
    }
    double computeBodyTemperature() const {
        return langevin ? langevin->computeBodyTemperature() : noseHoover->computeBodyTemperature();
    }
    double getTemperature() const {
        return langevin ? langevin->getTemperature() : noseHoover->getTemperature();
    }
    double getCoupling() const {
        return langevin ? langevin->getFriction() : noseHoover->getCollisionFrequency();
    }
    double getDrudeTemperature() const {
        return langevin ? langevin->getDrudeTemperature() : noseHoover->getDrudeTemperature();
    }
    void setDrudeTemperature(double temperature) const {
        langevin ? langevin->setDrudeTemperature(temperature) : noseHoover->setDrudeTemperature(temperature);
    }
    double getDrudeCoupling() const {
        return langevin ? langevin->getDrudeFriction() : noseHoover->getDrudeCollisionFrequency();
    }
    void setDrudeCoupling(double coupling) const {
        langevin ? langevin->setDrudeFriction(coupling) : noseHoover->setDrudeCollisionFrequency(coupling);
    }
    double getMaxDrudeDistance() const {
        return langevin ? langevin->getMaxDrudeDistance() : noseHoover->getMaxDrudeDistance();
    }
    void setMaxDrudeDistance(double distance) const {
        langevin ? langevin->setMaxDrudeDistance(distance) : noseHoover->setMaxDrudeDistance(distance);
    }
    /** Both chains' energy (Nose-Hoover); 0 for Langevin, which has no heat bath. */
    double heatBathEnergy() const {
        return noseHoover ? noseHoover->computeHeatBathEnergy() : 0.0;
    }
    MRattleDrudeLangevinIntegrator* langevin;
    MRattleDrudeNoseHooverIntegrator* noseHoover;
};

string kindName(const ::testing::TestParamInfo<string>& info) {
    return info.param;
}

/** The Drude integrators' kinds, without platforms: their settings (no Context). */
class DrudeSettings : public ::testing::TestWithParam<string> {};

TEST_P(DrudeSettings, BadSettingsAreRefused) {
    const string kind = GetParam();
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    const double coupling = isLangevin(kind) ? 1.0 : 10.0;
    for (double bad : {-1.0, nan, inf}) {
        EXPECT_THROW(DrudeView::make(kind, bad, coupling, 1.0, 20.0, 0.001), OpenMMException);
        EXPECT_THROW(DrudeView::make(kind, 300, bad, 1.0, 20.0, 0.001), OpenMMException);
        EXPECT_THROW(DrudeView::make(kind, 300, coupling, bad, 20.0, 0.001), OpenMMException);
        EXPECT_THROW(DrudeView::make(kind, 300, coupling, 1.0, bad, 0.001), OpenMMException);
        std::unique_ptr<RigidBodyIntegrator> integrator = DrudeView::make(kind, 300, coupling, 1.0, 20.0, 0.001);
        const DrudeView drude(*integrator);
        EXPECT_THROW(drude.setMaxDrudeDistance(bad), OpenMMException);
        EXPECT_THROW(drude.setDrudeTemperature(bad), OpenMMException);
        EXPECT_THROW(drude.setDrudeCoupling(bad), OpenMMException);
        // Unchanged by a refused setting: Langevin's default 0 (no wall), Nose-Hoover's OpenMM's 0.02 nm.
        EXPECT_EQ(drude.isLangevin() ? 0.0 : 0.02, drude.getMaxDrudeDistance());
        EXPECT_EQ(1.0, drude.getDrudeTemperature());
    }
    const string message = messageOf([&] { DrudeView::make(kind, 300, coupling, -1.0, 20.0, 0.001); });
    EXPECT_NE(string::npos, message.find(kind + "Integrator")) << message;
    EXPECT_NE(string::npos, message.find("Drude temperature")) << message;
    if (isLangevin(kind))
        return;
    // Nose-Hoover: the chains' masses are proportional to the temperatures: 0 K is refused for both.
    EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(0.0, 10.0, 1.0, 20.0, 0.001), OpenMMException);
    EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, 0.0, 20.0, 0.001), OpenMMException);
    EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, 1.0, 20.0, 0.001, 0), OpenMMException);
    EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, 1.0, 20.0, 0.001, 3, 0), OpenMMException);
    for (int order : {0, 2, 4, 9})
        EXPECT_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, 1.0, 20.0, 0.001, 3, 3, order), OpenMMException);
    for (int order : {1, 3, 5, 7})
        EXPECT_NO_THROW(MRattleDrudeNoseHooverIntegrator(300, 10.0, 1.0, 20.0, 0.001, 3, 3, order));
    MRattleDrudeNoseHooverIntegrator unbound(300, 10.0, 1.0, 20.0, 0.001);
    EXPECT_THROW(unbound.computeHeatBathEnergy(), OpenMMException);
}

TEST_P(DrudeSettings, SettingsRoundTripThroughXml) {
    const string kind = GetParam();
    std::unique_ptr<RigidBodyIntegrator> integrator;
    if (isLangevin(kind)) {
        auto* langevin = new MRattleDrudeLangevinIntegrator(310, 2.0, 1.5, 25.0, 0.0015);
        langevin->setRandomNumberSeed(17);
        integrator.reset(langevin);
    }
    else
        integrator.reset(new MRattleDrudeNoseHooverIntegrator(310, 2.0, 1.5, 25.0, 0.0015, 4, 2, 5));
    DrudeView(*integrator).setMaxDrudeDistance(0.03);
    std::unique_ptr<Integrator> copy = fromXml(toXml(*integrator));
    RigidBodyIntegrator& readIntegrator = dynamic_cast<RigidBodyIntegrator&>(*copy);
    const DrudeView read(readIntegrator);
    ASSERT_EQ(isLangevin(kind), read.isLangevin());
    EXPECT_EQ(310, read.getTemperature());
    EXPECT_EQ(2.0, read.getCoupling());
    EXPECT_EQ(1.5, read.getDrudeTemperature());
    EXPECT_EQ(25.0, read.getDrudeCoupling());
    EXPECT_EQ(0.03, read.getMaxDrudeDistance());
    EXPECT_EQ(0.0015, readIntegrator.getStepSize());
    if (read.langevin) {
        EXPECT_EQ(17, read.langevin->getRandomNumberSeed());
    }
    else {
        EXPECT_EQ(4, read.noseHoover->getChainLength());
        EXPECT_EQ(2, read.noseHoover->getNumMultiTimeSteps());
        EXPECT_EQ(5, read.noseHoover->getNumYoshidaSuzukiTimeSteps());
    }
}

INSTANTIATE_TEST_SUITE_P(Drude, DrudeSettings, ::testing::Values(langevinKind, noseHooverKind), kindName);

} // namespace

#ifdef MRATTLE_HAVE_DRUDE

using namespace MRattleTest::Drude;

namespace {

/** A State with its integrator parameters (a thermostat's chains) as OpenMM's XML, to compare whole. */
string stateXml(Context& context) {
    const State state = context.getState(State::Positions | State::Velocities | State::IntegratorParameters);
    std::stringstream xml;
    XmlSerializer::serialize<State>(&state, "State", xml);
    return xml.str();
}

/** Every platform that runs the Drude integrators, times both. */
class DrudeIntegrators : public ::testing::TestWithParam<Config> {
protected:
    void SetUp() override {
        MRATTLE_SKIP_IF_UNAVAILABLE(GetParam().platform);
    }
};

/** Both Drude integrators on Reference. */
class DrudeOnReference : public ::testing::TestWithParam<string> {};

void expectSame(const vector<Vec3>& before, const vector<Vec3>& after) {
    for (size_t i = 0; i < before.size(); i++)
        for (int k = 0; k < 3; k++)
            EXPECT_EQ(before[i][k], after[i][k]) << "particle " << i;
}

/** The largest change of a distance inside a body between two configurations. */
double worstBodyChange(const DrudeSystem& d, const vector<Vec3>& start, const vector<Vec3>& end) {
    double worst = 0;
    for (const vector<int>& body : d.bodies)
        for (size_t i = 0; i < body.size(); i++)
            for (size_t j = i + 1; j < body.size(); j++)
                worst = std::max(worst, std::fabs(distance(end[body[j]], end[body[i]]) -
                                                  distance(start[body[j]], start[body[i]])));
    return worst;
}

/**
 * 200 steps of each integrator, each in the Context contextFor makes for it, from the same
 * start: the first one's draw at 300 K with this seed (each integrator's
 * setVelocitiesToTemperature() draws its own way). The Contexts, in the integrators' order.
 */
vector<std::unique_ptr<Context> > runEach(const vector<RigidBodyIntegrator*>& integrators, int seed,
                                          const std::function<std::unique_ptr<Context>(RigidBodyIntegrator&)>& contextFor) {
    vector<std::unique_ptr<Context> > contexts;
    vector<Vec3> velocities;
    for (RigidBodyIntegrator* integrator : integrators) {
        contexts.push_back(contextFor(*integrator));
        if (velocities.empty()) {
            contexts.back()->setVelocitiesToTemperature(300, seed);
            velocities = contexts.back()->getState(State::Velocities).getVelocities();
        }
        contexts.back()->setVelocities(velocities);
        integrator->step(200);
    }
    return contexts;
}

/** Whether message holds what followed by the index (and no further digit). */
bool namesParticle(const string& message, const string& what, int index) {
    const string text = what + std::to_string(index);
    const size_t at = message.find(text);
    return at != string::npos && (at + text.size() == message.size() || !std::isdigit(message[at + text.size()]));
}

vector<Vec3> positionsOf(Context& context) {
    return context.getState(State::Positions).getPositions();
}

/**
 * A Context of the waters (no ions) for the integrator on a platform, at positions and
 * velocities from 3 ps of MRattleDrudeLangevinIntegrator (Reference) at 300 K and Drude 50 K
 * from the lattice: the cluster's collapse heats it to about 1000 K, which Langevin takes out
 * fast and a chain slowly. The warm-up has the hard wall (0.02 nm), as real SWM4-NDP runs.
 */
std::unique_ptr<Context> equilibratedWaters(const DrudeSystem& d, RigidBodyIntegrator& integrator,
                                            const string& platformName = "Reference",
                                            const std::map<string, string>& properties = {}) {
    MRattleDrudeLangevinIntegrator langevin(300, 5.0, 50, 20.0, 0.001);
    langevin.setRandomNumberSeed(3);
    langevin.setMaxDrudeDistance(0.02);
    std::unique_ptr<Context> warm = referenceContext(d, langevin);
    warm->setVelocitiesToTemperature(300, 3);
    langevin.step(3000);
    const State state = warm->getState(State::Positions | State::Velocities);
    std::unique_ptr<Context> context = platformContext(d, integrator, platformName, properties);
    context->setPositions(state.getPositions());
    context->setVelocities(state.getVelocities());
    return context;
}

TEST_P(DrudeIntegrators, ADrudeForceAddedAfterTheContextFailsTheStepUntilReinitialize) {
    DrudeSystem d = drudeWaters(2, 1, 0.4);
    d.system.removeForce(1);   // the DrudeForce: the Context starts without one
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(GetParam().integrator, 0.001);
    std::unique_ptr<Context> context = platformContext(d, *integrator, GetParam().platform,
                                                       platformProperties(GetParam().platform));
    integrator->step(2);
    DrudeForce* drude = new DrudeForce();
    for (const auto& pair : d.pairs)
        drude->addParticle(pair.first, pair.second, -1, -1, -1, -1.2, 0.001, 1.0, 1.0);
    d.system.addForce(drude);
    const State before = context->getState(State::Positions | State::Velocities);
    const string message = messageOf([&] { integrator->step(3); });
    EXPECT_NE(string::npos, message.find(GetParam().integrator)) << message;
    EXPECT_NE(string::npos, message.find("reinitialize")) << message;
    const State after = context->getState(State::Positions | State::Velocities);
    expectSame(before.getPositions(), after.getPositions());
    expectSame(before.getVelocities(), after.getVelocities());
    // More pairs in the same force: refused too; reinitialize() then sees them.
    context->reinitialize(true);
    integrator->step(2);
    drude->addParticle(d.bodies[0][1], d.bodies[0][0], -1, -1, -1, -0.1, 0.0001, 1.0, 1.0);
    EXPECT_NE(string::npos, messageOf([&] { integrator->step(1); }).find("reinitialize"));
}

TEST_P(DrudeIntegrators, VelocitiesForTemperatureDrawTheDrudeParticlesAtTheDrudeTemperature) {
    // No force at the start (no NonbondedForce, each Drude particle on its core): the shift by
    // half a step of the forces that setVelocitiesToTemperature() gives a leapfrog integrator
    // (OpenMM's, MRattleDrudeLangevin's) is then zero, and what is measured is the draw.
    DrudeSystem d = drudeWaters(27, 0, 0.4);
    d.system.removeForce(0);
    for (const auto& pair : d.pairs)
        d.positions[pair.first] = d.positions[pair.second];
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(GetParam().integrator, 0.001);
    std::unique_ptr<Context> context = platformContext(d, *integrator, GetParam().platform,
                                                       platformProperties(GetParam().platform));
    const DrudeView drude(*integrator);
    const double drudeTarget = 5.0;
    drude.setDrudeTemperature(drudeTarget);
    // Ten draws: 81 relative and 159 other degrees of freedom each, so each mean has a relative
    // standard error of about sqrt(2/810) = 5% (Drude) and 4% (bodies); allowed 4 of them.
    double drudeMean = 0, bodyMean = 0;
    const int draws = 10;
    for (int seed = 1; seed <= draws; seed++) {
        context->setVelocitiesToTemperature(300, seed);
        drudeMean += drude.computeDrudeTemperature() / draws;
        bodyMean += drude.computeBodyTemperature() / draws;
    }
    EXPECT_NEAR(drudeTarget, drudeMean, 4 * std::sqrt(2.0 / (81 * draws)) * drudeTarget);
    EXPECT_NEAR(300, bodyMean, 4 * std::sqrt(2.0 / (159 * draws)) * 300);
}

TEST_P(DrudeIntegrators, TemperaturesReachTheirTargetsAndACheckpointContinuesBitForBit) {
    // The platform's default precision (single on a device; CPU on one thread): the bodies at
    // 300 K and the Drude particles at 50 K within their statistical errors. Langevin: 8 waters
    // and 2 ions (51 degrees of freedom at 300 K, 30 Drude ones) with the wall of real SWM4-NDP
    // runs (0.02 nm), from the lattice; Nose-Hoover: 8 waters (48 and 24, OpenMM's default wall
    // 0.02 nm) from a Langevin warm-up, in steps of 0.5 fs (at 1 fs, omega h about 1 for the
    // Drude springs, the Drude temperature read 49.3-51.9 K over four warm-up seeds, two of
    // them more than 3 standard errors above 50). Then 50 steps after loading a checkpoint are
    // the 50 steps run on: positions, velocities and integrator parameters (the random stream
    // is in it; both chains).
    const string& name = GetParam().platform;
    const bool langevin = isLangevin(GetParam().integrator);
    const std::map<string, string> properties = isDevicePlatform(name) ? std::map<string, string>()
                                                                       : platformProperties(name);
    DrudeSystem d = drudeWaters(8, langevin ? 2 : 0, 0.34);
    const double temperature = 300, drudeTemperature = 50, stepSize = langevin ? 0.001 : 0.0005;
    std::unique_ptr<RigidBodyIntegrator> integrator = DrudeView::make(
        GetParam().integrator, temperature, langevin ? 5.0 : 10.0, drudeTemperature, 20.0, stepSize);
    const DrudeView drude(*integrator);
    std::unique_ptr<Context> context;
    if (langevin) {
        drude.langevin->setRandomNumberSeed(2024);
        drude.setMaxDrudeDistance(0.02);
        context = platformContext(d, *integrator, name, properties);
        context->setVelocitiesToTemperature(temperature, 3);
    }
    else
        context = equilibratedWaters(d, *integrator, name, properties);
    const int stepsPerSample = std::lround(0.01 / stepSize);   // 10 fs
    integrator->step(200 * stepsPerSample);
    vector<double> body, drudeSeries;
    for (int sample = 0; sample < 4000; sample++) {
        integrator->step(stepsPerSample);
        body.push_back(drude.computeBodyTemperature());
        drudeSeries.push_back(drude.computeDrudeTemperature());
    }
    const auto bodyMean = blockMean(body), drudeMean = blockMean(drudeSeries);
    std::cout << name << ", " << GetParam().integrator << ": body temperature " << bodyMean.first << " +- "
              << bodyMean.second << " K (target " << temperature << "), Drude temperature " << drudeMean.first
              << " +- " << drudeMean.second << " K (target " << drudeTemperature << ")" << std::endl;
    EXPECT_NEAR(temperature, bodyMean.first, 3 * bodyMean.second);
    // The Drude temperature within 3 standard errors and 2% of its target: with its Drude
    // particles at 50 K among motion at 300 K this system's Drude temperature sits above 50 K in
    // the steady state (2026-12-03, Reference, runs of this length, Langevin 5/ps and 20/ps,
    // mean +- standard error over seeds): MRattleDrudeLangevin 50.39 +- 0.09 K (24 seeds; 50.45
    // and 50.59 at 0.5 and 0.25 fs, 50.38 at a Drude friction of 80/ps), and OpenMM's
    // DrudeLangevinIntegrator (waters SETTLEd, its pair temperature) 50.44 +- 0.11 K at 0.1 fs
    // (at 1 fs its half-step velocities read 66 K). The excess is this system's interactions':
    // both integrators read about 0.3 K more with its NonbondedForce than without it
    // (MRattleDrudeLangevin at 1 fs 0.31 +- 0.16 K, 50.08 K without; OpenMM at 0.25 fs, from its
    // half-step and its centred velocities, 0.29 and 0.27 +- 0.18 K). Both read their target when the two
    // temperatures are equal (300 K: 299.5 +- 0.4 and 299.4 +- 0.9 K), and real SWM4-NDP reads
    // 50.03 +- 0.11 K. The excess, about one standard error of a run, made 3 of them fail about
    // 1 seed in 65 (instead of 1 in 370). OpenMM's own test allows 1% (one pair's internal
    // temperature) and 3% (SWM4-NDP water's): plugins/drude/tests/TestDrudeLangevinIntegrator.h,
    // OpenMM 7.7.0, lines 93 and 171. Not yet explained: OpenMM's excess falls with a larger
    // Drude friction (50.19 +- 0.07 K at 80/ps, 0.1 fs), as heat flowing in from the 300 K motion
    // would, while this plugin's stays (50.38 +- 0.05 K at 80/ps).
    EXPECT_NEAR(drudeTemperature, drudeMean.first, 3 * drudeMean.second + 0.02 * drudeTemperature);
    // Errors small enough for the check to mean something (a few per cent).
    EXPECT_LT(bodyMean.second, 0.03 * temperature);
    EXPECT_LT(drudeMean.second, 0.03 * drudeTemperature);
    std::stringstream checkpoint;
    context->createCheckpoint(checkpoint);
    const double bathAtCheckpoint = drude.heatBathEnergy();
    integrator->step(50);
    const string straight = stateXml(*context);
    const double bath = drude.heatBathEnergy();
    context->loadCheckpoint(checkpoint);
    EXPECT_EQ(bathAtCheckpoint, drude.heatBathEnergy());
    integrator->step(50);
    EXPECT_EQ(straight, stateXml(*context));
    EXPECT_EQ(bath, drude.heatBathEnergy());
    if (!langevin) {
        EXPECT_NE(0.0, bath);
        // The State names both chains' variables.
        for (const char* variable : {"chainPositions", "chainVelocities", "drudeChainPositions", "drudeChainVelocities"})
            EXPECT_NE(string::npos, straight.find(variable)) << variable;
    }
}

TEST_P(DrudeIntegrators, TheWallActsAsOnReferenceAndAFailedStepLeavesTheStateAsBefore) {
    // A wall at 0.002 nm that the Drude particles (0.004 nm at 300 K) reach often, steps of
    // 0.25 fs. Langevin without frictions (deterministic), Nose-Hoover with both chains coupled.
    // On a device platform (double precision): 200 steps from the same state follow Reference's
    // bounces (and chains), and without the wall Reference ends far from both. Then on every
    // platform a Drude particle sent off at 40 nm/ps (0.01 nm in a step, from at most 0.002 nm
    // off its core) crosses twice the wall: the step is refused naming the particle and its
    // core, and positions, velocities, both chains and the step count are as before it.
    const string& name = GetParam().platform;
    const bool langevin = isLangevin(GetParam().integrator);
    DrudeSystem d = drudeWaters(2, 1, 0.4);
    const double wall = 0.002;
    auto make = [&]() {
        return langevin ? DrudeView::make(GetParam().integrator, 300, 0.0, 300, 0.0, 0.00025)
                        : DrudeView::make(GetParam().integrator, 300, 10.0, 50, 20.0, 0.00025);
    };
    std::unique_ptr<RigidBodyIntegrator> withoutWall = make(), onReference = make(), onPlatform = make();
    const bool compare = isDevicePlatform(name);
    vector<RigidBodyIntegrator*> runs = {onPlatform.get()};
    if (compare)
        runs = {withoutWall.get(), onReference.get(), onPlatform.get()};
    for (RigidBodyIntegrator* integrator : runs)
        DrudeView(*integrator).setMaxDrudeDistance(integrator == withoutWall.get() ? 0.0 : wall);
    vector<std::unique_ptr<Context> > contexts = runEach(runs, 5, [&](RigidBodyIntegrator& integrator) {
        return &integrator != onPlatform.get() ? referenceContext(d, integrator)
                                               : platformContext(d, integrator, name, platformProperties(name));
    });
    vector<vector<Vec3> > positions;
    vector<double> baths;
    for (size_t k = 0; k < runs.size(); k++) {
        positions.push_back(positionsOf(*contexts[k]));
        baths.push_back(DrudeView(*runs[k]).heatBathEnergy());
    }
    Context* context = contexts.back().get();
    const DrudeView drude(*onPlatform);
    EXPECT_LE(farthestDrude(d, positions.back()), wall * (1 + 1e-9));
    if (compare) {
        const double deviation = maxDeviation(positions[1], positions[2]);
        std::cout << name << ", " << GetParam().integrator << ": after 200 steps " << deviation
                  << " nm from Reference, heat bath " << baths[2] << " kJ/mol (Reference's " << baths[1]
                  << "); Reference without the wall " << maxDeviation(positions[0], positions[1]) << " nm away"
                  << std::endl;
        EXPECT_LT(deviation, 1e-7);
        EXPECT_GT(maxDeviation(positions[0], positions[2]), 1e-4);   // the wall acted
        if (!langevin) {
            EXPECT_NEAR(baths[1], baths[2], 1e-6 * std::fabs(baths[1]));
            EXPECT_GT(std::fabs(baths[1]), 0.1);   // the chains moved
        }
    }
    vector<Vec3> v = context->getState(State::Velocities).getVelocities();
    const int particle = d.pairs[0].first;
    v[particle] += Vec3(40.0, 0, 0);
    context->setVelocities(v);
    const string before = stateXml(*context);
    const double bath = drude.heatBathEnergy();
    const int steps = context->getState(0).getStepCount();
    const string message = messageOf([&] { onPlatform->step(1); });
    EXPECT_NE(string::npos, message.find("beyond twice the hard wall")) << message;
    // Every platform names the particle and its core by System index (a device: the pair its
    // failing work item recorded, read once the failure is found).
    EXPECT_NE(string::npos, message.find("Drude particle " + std::to_string(particle) + " ")) << message;
    EXPECT_NE(string::npos, message.find("its core " + std::to_string(d.pairs[0].second))) << message;
    EXPECT_NE(string::npos, message.find(drude.className())) << message;
    EXPECT_EQ(before, stateXml(*context));
    EXPECT_EQ(bath, drude.heatBathEnergy());
    EXPECT_EQ(steps, context->getState(0).getStepCount());
    if (!langevin) {
        EXPECT_NE(0.0, bath);
    }
}

/**
 * 4 waters and an ion without the NonbondedForce, each Drude particle 0.015 nm off its core, and
 * velocities with the waters turning fast (|w| = 54/ps about their oxygens) and each Drude
 * particle at its core's velocity plus relative (an empty relative list: none).
 */
struct TurningWaters {
    explicit TurningWaters() : d(drudeWaters(4, 1, 0.4)) {
        d.system.removeForce(0);
        for (const auto& pair : d.pairs)
            d.positions[pair.first] = d.positions[pair.second] + offset;
    }
    vector<Vec3> velocities(const vector<Vec3>& relative) const {
        vector<Vec3> v(d.system.getNumParticles(), drift);
        for (const vector<int>& body : d.bodies)
            for (int atom : body)
                v[atom] = drift + omega.cross(d.positions[atom] - d.positions[body[0]]);
        for (size_t k = 0; k < d.pairs.size(); k++)
            v[d.pairs[k].first] = v[d.pairs[k].second] + (relative.empty() ? Vec3() : relative[k]);
        return v;
    }
    DrudeSystem d;
    const Vec3 offset = Vec3(0.8, 0.0, -0.6) * 0.015, omega = Vec3(30, -20, 40), drift = Vec3(0.3, -0.2, 0.1);
};

TEST_P(DrudeIntegrators, TheDrudeTemperatureIsTheDrudeParticlesMotionRelativeToTheirCores) {
    // Drude particles moving with their cores have none, though their bodies turn (carried by the
    // rotation, w x (r_drude - r_core), they would read 8 K); with relative velocities u it is
    // OpenMM's sum mu |u|^2 / (3 n k_B), mu the pair's reduced mass, within the recoil of the
    // core's whole body (O(m_drude / M), M the body's mass: 2% for a water), exact for the ion.
    const TurningWaters turning;
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(GetParam().integrator, 0.001);
    std::unique_ptr<Context> context = platformContext(turning.d, *integrator, GetParam().platform,
                                                       platformProperties(GetParam().platform));
    const DrudeView drude(*integrator);
    context->setVelocities(turning.velocities({}));
    EXPECT_LT(drude.computeDrudeTemperature(), 1e-6);
    vector<Vec3> carried = turning.velocities({});
    for (size_t k = 0; k < 4; k++)
        carried[turning.d.pairs[k].first] += turning.omega.cross(turning.offset);
    context->setVelocities(carried);
    EXPECT_GT(drude.computeDrudeTemperature(), 5.0);
    vector<Vec3> relative;
    double expected = 0;
    const vector<double> m = masses(turning.d.system);
    for (size_t k = 0; k < turning.d.pairs.size(); k++) {
        relative.push_back(Vec3(1.0 + k, -0.5 * k, 0.7) * 0.3);
        const double mu = 1 / (1 / m[turning.d.pairs[k].first] + 1 / m[turning.d.pairs[k].second]);
        expected += mu * relative.back().dot(relative.back()) / (3 * turning.d.pairs.size() * BOLTZ);
    }
    context->setVelocities(turning.velocities(relative));
    EXPECT_NEAR(expected, drude.computeDrudeTemperature(), 0.01 * expected);   // measured: 0.04% off
}

TEST_P(DrudeIntegrators, LangevinsStrongDrudeFrictionLeavesTheDrudeParticlesMovingWithTheirCores) {
    // Drude friction 1e6/ps at 0 K and none on the bodies, from the turning waters with their
    // Drude particles carried by the rotation: one step's O takes every relative motion away
    // and leaves each body's turning (with a split about the rotation, ALGORITHM.md's first
    // one, 8 K would stay); what remains is the drift's half step after O.
    if (!isLangevin(GetParam().integrator))
        GTEST_SKIP() << "a Langevin property (Nose-Hoover's Drude chain scales, its tests are the chains')";
    const TurningWaters turning;
    MRattleDrudeLangevinIntegrator integrator(0.0, 0.0, 0.0, 1e6, 0.001);
    std::unique_ptr<Context> context = platformContext(turning.d, integrator, GetParam().platform,
                                                       platformProperties(GetParam().platform));
    vector<Vec3> carried = turning.velocities({});
    for (size_t k = 0; k < 4; k++)
        carried[turning.d.pairs[k].first] += turning.omega.cross(turning.offset);
    context->setVelocities(carried);
    ASSERT_GT(integrator.computeDrudeTemperature(), 5.0);
    const double bodies = integrator.computeBodyTemperature();
    integrator.step(1);
    EXPECT_LT(integrator.computeDrudeTemperature(), 0.05);
    EXPECT_GT(integrator.computeBodyTemperature(), 0.5 * bodies);
}

TEST_P(DrudeIntegrators, LangevinsDrudeNoiseAloneKeepsMomentum) {
    // Without friction on the bodies only C is thermostatted: its noise and friction move each
    // group's Drude particles with zero momentum, and the forces (vacuum, no cutoff) and
    // M-RATTLE keep it, so the total stays as it began. (Not angular momentum: C turns a Drude
    // particle about its core, as OpenMM's pair thermostat does.) On Reference and, in double
    // precision, on each device platform.
    if (!isLangevin(GetParam().integrator))
        GTEST_SKIP() << "a Langevin property (Nose-Hoover's Drude chain scales, its tests are the chains')";
    const string& name = GetParam().platform;
    if (name == "CPU")   // measured: 1.6e-5 in momentum
        GTEST_SKIP() << "the CPU platform's forces are single precision: momentum drifts by their round-off";
    DrudeSystem d = drudeWaters(4, 0, 0.32);
    MRattleDrudeLangevinIntegrator integrator(300, 0.0, 50, 20.0, 0.001);
    integrator.setRandomNumberSeed(9);
    std::unique_ptr<Context> context = platformContext(d, integrator, name, platformProperties(name));
    context->setVelocitiesToTemperature(300, 8);
    const vector<double> m = masses(d.system);
    const State start = context->getState(State::Velocities);
    integrator.step(1000);
    const State end = context->getState(State::Velocities);
    const Vec3 p0 = totalMomentum(m, start.getVelocities()), p1 = totalMomentum(m, end.getVelocities());
    for (int k = 0; k < 3; k++)
        EXPECT_NEAR(p0[k], p1[k], 1e-9) << "momentum, axis " << k;
    // The Drude particles did get the noise: they are near 50 K, not at the start's 300 K.
    EXPECT_LT(integrator.computeDrudeTemperature(), 150);
}

TEST_P(DrudeOnReference, BodiesWithDrudeCoresStayRigid) {
    const string kind = GetParam();
    if (isLangevin(kind)) {
        // 4 waters and a free ion from the lattice, 2000 steps: the Drude particles move
        // relative to their cores (they are not held), and stay near them; the free pair's
        // core moves (it is free, not frozen).
        DrudeSystem d = drudeWaters(4, 1, 0.32);
        MRattleDrudeLangevinIntegrator integrator(300, 5.0, 1.0, 20.0, 0.001);
        integrator.setRandomNumberSeed(11);
        std::unique_ptr<Context> context = referenceContext(d, integrator);
        context->setVelocitiesToTemperature(300, 5);
        const State start = context->getState(State::Positions);
        integrator.step(2000);
        const State end = context->getState(State::Positions | State::Velocities);
        EXPECT_LT(worstBodyChange(d, start.getPositions(), end.getPositions()), 1e-10);
        for (const auto& pair : d.pairs) {
            const double separation = distance(end.getPositions()[pair.first], end.getPositions()[pair.second]);
            EXPECT_GT(separation, 0.0) << "Drude particle " << pair.first;
            EXPECT_LT(separation, 0.02) << "Drude particle " << pair.first;
        }
        const int ion = d.pairs.back().second;
        EXPECT_GT(distance(start.getPositions()[ion], end.getPositions()[ion]), 1e-3);
        // Degrees of freedom: 6 per water, 3 per Drude particle, 3 for the ion's core.
        EXPECT_EQ(4 * 6 + 5 * 3 + 3, integrator.getNumDegreesOfFreedom());
        return;
    }
    // Nose-Hoover: 8 warmed-up waters without the wall (which is not Hamiltonian), 2000 steps
    // of 0.5 fs: the chains move energy in and out by tens of kJ/mol; kinetic + potential +
    // bath moves by the step's error only.
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
    EXPECT_LT(worstBodyChange(d, start.getPositions(), end.getPositions()), 1e-10);
    EXPECT_EQ(8 * 6 + 8 * 3, integrator.getNumDegreesOfFreedom());
}

TEST_P(DrudeOnReference, WithoutCouplingItIsItsPlainCounterpart) {
    // Both couplings 0 and no wall: no noise and no scaling. Langevin: MRattleLangevinIntegrator's
    // step at zero friction (one drift); Nose-Hoover: the chains rest and the step is
    // MRattleIntegrator's velocity Verlet. Bit for bit.
    const string kind = GetParam();
    DrudeSystem d = drudeWaters(3, 1, 0.32);
    std::unique_ptr<RigidBodyIntegrator> plain;
    if (isLangevin(kind))
        plain.reset(new MRattleLangevinIntegrator(300, 0.0, 0.001));
    else
        plain.reset(new MRattleIntegrator(0.001));
    std::unique_ptr<RigidBodyIntegrator> integrator = DrudeView::make(kind, 300, 0.0, 1.0, 0.0, 0.001);
    DrudeView(*integrator).setMaxDrudeDistance(0);
    const vector<std::unique_ptr<Context> > contexts = runEach(
        {plain.get(), integrator.get()}, 4, [&](RigidBodyIntegrator& each) { return referenceContext(d, each); });
    expectSame(positionsOf(*contexts[0]), positionsOf(*contexts[1]));
}

TEST_P(DrudeOnReference, NoseHooverWithoutDrudeParticlesIsMRattleNoseHoover) {
    // A System with no DrudeForce pair: the body chain sees all the kinetic energy and all
    // degrees of freedom, the Drude chain rests: MRattleNoseHooverIntegrator's step, bit for bit.
    // (Langevin without a DrudeForce is MRattleLangevin with draws of its own: TestSupport's traits.)
    if (isLangevin(GetParam()))
        GTEST_SKIP() << "a Nose-Hoover property (Langevin draws its own noise)";
    DrudeSystem d = drudeWaters(3, 0, 0.32);
    for (int f = 0; f < d.system.getNumForces(); f++)
        if (dynamic_cast<DrudeForce*>(&d.system.getForce(f))) {
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
    const vector<std::unique_ptr<Context> > contexts =
        runEach({&chain, &drude}, 4, [&](RigidBodyIntegrator& each) { return referenceContext(d, each); });
    expectSame(positionsOf(*contexts[0]), positionsOf(*contexts[1]));
}

TEST_P(DrudeOnReference, ADrudeParticleInABodyIsRefusedNamingIt) {
    const string kind = GetParam();
    DrudeSystem d = drudeWaters(2, 0, 0.4);
    std::unique_ptr<RigidBodyIntegrator> integrator = DrudeView::make(kind, 300, 1.0, 1.0, 20.0, 0.001);
    integrator->addRigidBody({0, 1, 2});
    integrator->addRigidBody({4, 5, 6, 7});   // water 1 with its Drude particle 7
    const string message = messageOf([&] { Context context(d.system, *integrator, platform("Reference")); });
    EXPECT_NE(string::npos, message.find(kind + "Integrator")) << message;
    EXPECT_NE(string::npos, message.find("Drude particle 7")) << message;
    // Bodies left to the molecules take the Drude particles in (DrudeForce bonds them): refused too.
    std::unique_ptr<RigidBodyIntegrator> byMolecules = DrudeView::make(kind, 300, 1.0, 1.0, 20.0, 0.001);
    const string byMoleculesMessage = messageOf([&] { Context context(d.system, *byMolecules, platform("Reference")); });
    EXPECT_NE(string::npos, byMoleculesMessage.find("Drude particle 3")) << byMoleculesMessage;
    EXPECT_NE(string::npos, byMoleculesMessage.find("addRigidBody")) << byMoleculesMessage;
}

TEST_P(DrudeOnReference, AMasslessCoreIsRefused) {
    DrudeSystem d = drudeWaters(0, 1, 0.4);
    d.system.setParticleMass(0, 0.0);
    std::unique_ptr<RigidBodyIntegrator> integrator = DrudeView::make(GetParam(), 300, 1.0, 1.0, 20.0, 0.001);
    const string message = messageOf([&] { Context context(d.system, *integrator, platform("Reference")); });
    EXPECT_NE(string::npos, message.find("without mass")) << message;
}

TEST_P(DrudeOnReference, LangevinsHardWallKeepsDrudeParticlesNearTheirCores) {
    // Drude particles at 300 K are about 0.004 nm from their cores (sqrt(3 kT / k)): a wall
    // at 0.005 nm is reached, and holds them within it at every step's end, the cores in
    // bodies and the free one alike. A short step (omega h = 0.25) keeps a step's motion
    // well inside twice the wall, where the step would fail. From rest: Langevin's noise
    // heats them (a chain scales what motion there is).
    if (!isLangevin(GetParam()))
        GTEST_SKIP() << "a Langevin test (from rest, which a chain does not heat)";
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
        farthest = std::max(farthest, farthestDrude(d, state.getPositions()));
        // The bodies stay rigid through the bounces.
        for (const vector<int>& body : d.bodies)
            EXPECT_NEAR(distance(start.getPositions()[body[0]], start.getPositions()[body[1]]),
                        distance(state.getPositions()[body[0]], state.getPositions()[body[1]]), 1e-10);
    }
    EXPECT_LE(farthest, wall * (1 + 1e-9));
    EXPECT_GT(farthest, 0.9 * wall);
}

TEST_P(DrudeOnReference, LangevinsHotDrudeParticleBeyondTwiceTheWallFailsTheStep) {
    // Hot Drude particles (3000 K) with a 1 fs step cross twice a 0.004 nm wall in one step of
    // their own noise: that step is refused, naming it, with the state as before it.
    if (!isLangevin(GetParam()))
        GTEST_SKIP() << "a Langevin test (from rest, which a chain does not heat)";
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

TEST(DrudeReordering, DrudeGroupsFollowTheDevicesReorderingsAsOnReference) {
    // A device platform reorders atoms when a nonbonded force has a cutoff (OpenMM 7.7: at the
    // end of the first step, then every 250 steps; whole identical molecules, sorted by position
    // and wrapped into the box), and CommonRigidBodyState::mapAtoms then uploads the Drude
    // groups' and pairs' device indices anew. 22 waters and 5 ions filling a periodic lattice
    // (0.4 nm, cutoff 0.55 nm; OpenMM's zigzag order is not the lattice's: through pocl about
    // 95 of the 108 atoms leave their System index, before the first step and at step 251),
    // Nose-Hoover with both chains coupled (deterministic; its Drude kernels read the groups,
    // the wall the pairs) and a wall that acts: 260 steps of 0.25 fs from the same state on
    // each device platform in double precision end close to Reference (2e-8 nm through pocl),
    // the Drude particles within the wall and the bodies rigid. One device Context a platform.
    // Three 75-atom polarizable bodies (Drude groups of 83, a work group each) are placed
    // against OpenMM's Hilbert order, so that through pocl a reordering moves all 249 of their
    // particles and they take the large-group kernels through it too.
    //
    // What this can and cannot catch: OpenMM moves only whole identical molecules (its
    // molecules join the bodies, CommonRigidBodyState's BodyForceInfo, and each Drude pair),
    // and a Drude group keeps nothing of its own on the device, so Drude lists left in the old
    // order only relabel the groups: skipping the upload of drudePairAtoms (or of every Drude
    // list) at a reordering passes, bit for bit. A list that pairs a group with another's
    // Drude pairs (drudePairAtoms rotated by one pair at each reordering) fails: 0.007 nm from
    // Reference. Then a Drude particle set 3.5 walls from its core
    // fails the next step, and the message names it and its core by System index.
    const double wall = 0.004, cutoff = 0.55;
    const int steps = 260;
    DrudeSystem d = drudeWaters(22, 5, 0.4, cutoff);
    const int firstBlobAtom = d.system.getNumParticles();
    addPolarizableBlobs(d, 3, 75);
    for (size_t i = firstBlobAtom; i < d.positions.size(); i++)
        d.positions[i] = Vec3(9.0 - d.positions[i][0], d.positions[i][1] + 0.6, d.positions[i][2] + 0.6);
    auto make = [&](double maxDistance) {
        std::unique_ptr<RigidBodyIntegrator> integrator =
            DrudeView::make(noseHooverKind, 300, 10.0, 50, 20.0, 0.00025);
        DrudeView(*integrator).setMaxDrudeDistance(maxDistance);
        return integrator;
    };
    std::unique_ptr<RigidBodyIntegrator> onReference = make(wall), withoutWall = make(0.0);
    std::unique_ptr<Context> reference = referenceContext(d, *onReference);
    reference->setVelocitiesToTemperature(300, 7);
    const vector<Vec3> velocities = reference->getState(State::Velocities).getVelocities();
    onReference->step(steps);
    const vector<Vec3> expected = positionsOf(*reference);
    EXPECT_LE(farthestDrude(d, expected), wall * (1 + 1e-9));
    std::unique_ptr<Context> unwalled = referenceContext(d, *withoutWall);
    unwalled->setVelocities(velocities);
    withoutWall->step(steps);
    EXPECT_GT(maxDeviation(expected, positionsOf(*unwalled)), 1e-4);   // the wall acted
    int ran = 0;
    for (const string& name : devicePlatforms()) {
        if (!unavailable(name).empty())
            continue;
        std::unique_ptr<RigidBodyIntegrator> onDevice = make(wall);
        std::unique_ptr<Context> context = platformContext(d, *onDevice, name, platformProperties(name));
        context->setVelocities(velocities);
        onDevice->step(steps);
        const vector<Vec3> positions = positionsOf(*context);
        const double deviation = maxDeviation(expected, positions);
        std::cout << name << ": " << steps << " steps through reorderings, " << deviation
                  << " nm from Reference; heat bath " << DrudeView(*onDevice).heatBathEnergy() << " kJ/mol (Reference's "
                  << DrudeView(*onReference).heatBathEnergy() << ")" << std::endl;
        EXPECT_LT(deviation, 1e-7) << name;
        EXPECT_LE(farthestDrude(d, positions), wall * (1 + 1e-9)) << name;
        EXPECT_LT(worstBodyChange(d, d.positions, positions), 1e-10) << name;
        // A wall failure found after the reorderings names the pair by System indices.
        const std::pair<int, int> pair = d.pairs[7];
        vector<Vec3> moved = positions;
        moved[pair.first] = moved[pair.second] + Vec3(3.5 * wall, 0, 0);
        context->setPositions(moved);
        const string message = messageOf([&] { onDevice->step(1); });
        EXPECT_TRUE(namesParticle(message, "Drude particle ", pair.first)) << name << ": " << message;
        EXPECT_TRUE(namesParticle(message, "core ", pair.second)) << name << ": " << message;
        ran++;
    }
    // Device platforms only (Reference is the yardstick): a build or machine without one has nothing to compare.
    if (ran == 0)
        GTEST_SKIP() << "no device platform here";
}

vector<Config> drudeConfigs() {
    vector<Config> configs;
    for (const string& kind : {langevinKind, noseHooverKind})
        for (const Config& config : configsOf(kind))
            configs.push_back(config);
    return configs;
}

INSTANTIATE_TEST_SUITE_P(Drude, DrudeIntegrators, ::testing::ValuesIn(drudeConfigs()), configName);
INSTANTIATE_TEST_SUITE_P(Drude, DrudeOnReference, ::testing::Values(langevinKind, noseHooverKind), kindName);

} // namespace

#endif // MRATTLE_HAVE_DRUDE
