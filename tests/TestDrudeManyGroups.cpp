/*
 * The Drude integrators on the device platforms with many Drude groups or large ones:
 * MRattleDrudeNoseHooverIntegrator with more Drude groups than one work group holds (300
 * polarizable waters), whose relative kinetic energy is summed by every work group and the
 * partial sums added by the chains' kernel; and both integrators with Drude groups of bodies
 * above the large-body threshold, which a work group each takes through the Drude phases (the
 * noise split, the wall, the relative kinetic energy, the chains' scaling). In double
 * precision the step follows Reference's and the chains move as on Reference.
 */
#include "DrudeTestSystem.h"
#include "MRattleDrudeLangevinIntegrator.h"
#include "MRattleDrudeNoseHooverIntegrator.h"
#include "TestSupport.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <gtest/gtest.h>
#include <cmath>
#include <functional>
#include <type_traits>
#include <iostream>
#include <map>
#include <random>
#include <tuple>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

#ifdef MRATTLE_HAVE_DRUDE

using namespace MRattleTest::Drude;

namespace {

/** Runs check on every device platform that runs here; false if there is none. */
bool onEachDevicePlatform(const std::function<void(const string&)>& check) {
    bool any = false;
    for (const string& name : devicePlatforms())
        if (unavailable(name).empty()) {
            any = true;
            check(name);
        }
    return any;
}

/** What a run ended with: [0] on Reference, [1] on the device. */
struct PairedRuns {
    vector<vector<Vec3> > positions;
    vector<double> baths, drudeTemperatures;
};

/** The same steps on Reference and on a device platform (double precision), from the same velocities. */
template <class Integrator>
PairedRuns runOnReferenceAndDevice(const string& platformName, const DrudeSystem& d,
                                   const std::function<Integrator*()>& make, double wall, int steps) {
    PairedRuns runs;
    vector<Vec3> velocities;
    for (bool onDevice : {false, true}) {
        std::unique_ptr<Integrator> integrator(make());
        integrator->setMaxDrudeDistance(wall);
        std::unique_ptr<Context> context = (onDevice ? platformContext(d, *integrator, platformName, {{"Precision", "double"}})
                                                     : referenceContext(d, *integrator));
        if (velocities.empty()) {
            context->setVelocitiesToTemperature(300, 7);
            velocities = context->getState(State::Velocities).getVelocities();
        }
        context->setVelocities(velocities);
        integrator->step(steps);
        runs.positions.push_back(context->getState(State::Positions).getPositions());
        runs.drudeTemperatures.push_back(integrator->computeDrudeTemperature());
        if constexpr (std::is_same<Integrator, MRattleDrudeNoseHooverIntegrator>::value)
            runs.baths.push_back(integrator->computeHeatBathEnergy());
    }
    return runs;
}

MRattleDrudeNoseHooverIntegrator* noseHoover() {
    return new MRattleDrudeNoseHooverIntegrator(300, 20.0, 1, 40.0, 0.0005);
}

} // namespace

TEST(DrudeManyGroups, TheChainsFollowReferenceAcrossWorkGroups) {
    const int numWaters = 300;   // Drude groups: more than 2 work groups of REDUCTION_THREADS (128)
    const bool any = onEachDevicePlatform([&](const string& name) {
        const PairedRuns runs = runOnReferenceAndDevice<MRattleDrudeNoseHooverIntegrator>(
            name, drudeWaters(numWaters, 0, 0.34), noseHoover, 0.02, 25);
        const double deviation = maxDeviation(runs.positions[0], runs.positions[1]);
        std::cout << name << ": " << numWaters << " Drude groups, after 25 steps " << deviation
                  << " nm from Reference; heat bath " << runs.baths[1] << " kJ/mol (Reference's " << runs.baths[0]
                  << "); Drude temperature " << runs.drudeTemperatures[1] << " K (Reference's "
                  << runs.drudeTemperatures[0] << ")" << std::endl;
        EXPECT_LT(deviation, 1e-7) << name;
        EXPECT_NEAR(runs.baths[0], runs.baths[1], 1e-6 * std::fabs(runs.baths[0])) << name;
        EXPECT_GT(std::fabs(runs.baths[0]), 1.0) << name;   // the chains moved
        EXPECT_NEAR(runs.drudeTemperatures[0], runs.drudeTemperatures[1], 1e-6 * runs.drudeTemperatures[0]) << name;
    });
    // Device platforms only (Reference is the yardstick): a build or machine without one has nothing to compare.
    if (!any)
        GTEST_SKIP() << "no device platform here";
}

TEST(DrudeManyGroups, LargeBodiesDrudeGroupsFollowReference) {
    // Three 75-atom bodies, each with 8 Drude particles about 0.0045 nm off their cores (groups
    // of 83), beside 8 waters and 2 ions; 40 steps with a wall at 0.004 nm that acts from the
    // first step. Langevin at 0 K (friction and the wall's bounce, no noise) and Nose-Hoover.
    const bool any = onEachDevicePlatform([](const string& name) {
        DrudeSystem d = drudeWaters(8, 2, 0.34);
        addPolarizableBlobs(d, 3, 75);
        const PairedRuns langevin = runOnReferenceAndDevice<MRattleDrudeLangevinIntegrator>(
            name, d, [] { return new MRattleDrudeLangevinIntegrator(0, 5.0, 0, 20.0, 0.0005); }, 0.004, 40);
        const PairedRuns hoover = runOnReferenceAndDevice<MRattleDrudeNoseHooverIntegrator>(name, d, noseHoover, 0.004, 40);
        for (const auto& labelled : {std::make_pair("Langevin at 0 K", &langevin), std::make_pair("Nose-Hoover", &hoover)}) {
            const PairedRuns& runs = *labelled.second;
            const double deviation = maxDeviation(runs.positions[0], runs.positions[1]);
            std::cout << name << " " << labelled.first << ", Drude groups of 83 particles: after 40 steps " << deviation
                      << " nm from Reference, bodies rigid to " << maxDistanceChange(d.positions, runs.positions[1], d.bodies)
                      << " nm" << std::endl;
            EXPECT_LT(deviation, 1e-7) << labelled.first;  // fixed-point device forces: 3e-8 measured
            EXPECT_GT(maxDeviation(d.positions, runs.positions[0]), 1e-3) << "the bodies moved";
            EXPECT_LT(maxDistanceChange(d.positions, runs.positions[1], d.bodies), 1e-11) << labelled.first;
            EXPECT_LE(farthestDrude(d, runs.positions[1]), 0.004 * (1 + 1e-9)) << "the wall held the Drude particles";
        }
        EXPECT_NEAR(hoover.baths[0], hoover.baths[1], 1e-6 * std::fabs(hoover.baths[0]));
        EXPECT_GT(std::fabs(hoover.baths[0]), 0.1) << "the chains moved";
    });
    if (!any)
        GTEST_SKIP() << "no device platform here";
}

namespace {

/** Mean and standard error of the Drude and body temperatures, sampled every 10 steps after 1000 of equilibration. */
struct SampledTemperatures {
    std::pair<double, double> drude, body;
};

SampledTemperatures sampleTemperatures(const DrudeSystem& d, const string& platformName,
                                       const std::map<string, string>& properties, int samples) {
    MRattleDrudeLangevinIntegrator integrator(300, 20.0, 30, 50.0, 0.0005);
    integrator.setRandomNumberSeed(platformName == "Reference" ? 11 : 12);
    std::unique_ptr<Context> context = platformContext(d, integrator, platformName, properties);
    // Every particle at 300 K, so the Drude particles start 10 times warmer than their thermostat.
    std::mt19937 random(13);
    std::normal_distribution<double> gaussian;
    vector<Vec3> velocities;
    for (int i = 0; i < d.system.getNumParticles(); i++) {
        const double scale = std::sqrt(BOLTZ * 300 / d.system.getParticleMass(i));
        velocities.push_back(Vec3(gaussian(random), gaussian(random), gaussian(random)) * scale);
    }
    context->setVelocities(velocities);
    integrator.step(1000);
    vector<double> drude, body;
    for (int k = 0; k < samples; k++) {
        integrator.step(10);
        drude.push_back(integrator.computeDrudeTemperature());
        body.push_back(integrator.computeBodyTemperature());
    }
    return {blockMean(drude), blockMean(body)};
}

} // namespace

TEST(DrudeManyGroups, LargeBodiesDrudeNoiseSamplesAsOnReference) {
    // The noise split of Drude groups above the threshold, with noise: three 75-atom bodies
    // with 8 Drude particles each (no charge, so only their springs act) beside 4 waters;
    // bodies at 300 K, Drude particles at 30 K, all starting at 300 K (so a group the noise
    // phase missed would stay warm). 1,000 steps, then 4,000 sampled on
    // Reference and on each device platform in its default, single precision: the mean Drude
    // and body temperatures agree within 4 combined standard errors (20 block means each).
    DrudeSystem d = drudeWaters(4, 0, 0.34);
    addPolarizableBlobs(d, 3, 75);
    const int samples = 400;
    const SampledTemperatures reference = sampleTemperatures(d, "Reference", {}, samples);
    const bool any = onEachDevicePlatform([&](const string& name) {
        const SampledTemperatures device = sampleTemperatures(d, name, {{"Precision", "single"}}, samples);
        for (const auto& labelled : {std::make_tuple("Drude", reference.drude, device.drude),
                                     std::make_tuple("body", reference.body, device.body)}) {
            const auto& [label, onReference, onDevice] = labelled;
            const double error = std::hypot(onReference.second, onDevice.second);
            std::cout << name << ": " << label << " temperature " << onDevice.first << " +- " << onDevice.second
                      << " K, Reference " << onReference.first << " +- " << onReference.second << " K" << std::endl;
            EXPECT_LT(std::fabs(onDevice.first - onReference.first), 4 * error) << name << ", " << label;
            EXPECT_LT(error, 0.05 * onReference.first) << name << ", " << label << ": too noisy to tell";
        }
    });
    EXPECT_LT(reference.drude.first, 40.0) << "the Drude thermostat cooled them";
    if (!any)
        GTEST_SKIP() << "no device platform here";
}

#else

TEST(DrudeManyGroups, NeedsOpenMMsDrudePlugin) {
    GTEST_SKIP() << "built without OpenMM's Drude plugin";
}

#endif
