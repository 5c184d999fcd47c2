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
#include <gtest/gtest.h>
#include <cmath>
#include <functional>
#include <type_traits>
#include <iostream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

#ifdef MRATTLE_HAVE_DRUDE

using namespace MRattleTest::Drude;

TEST(DrudeManyGroups, TheChainsFollowReferenceAcrossWorkGroups) {
    const int numWaters = 300;   // Drude groups: more than 2 work groups of REDUCTION_THREADS (128)
    bool any = false;
    for (const string& name : devicePlatforms()) {
        if (!unavailable(name).empty())
            continue;
        any = true;
        DrudeSystem d = drudeWaters(numWaters, 0, 0.34);
        MRattleDrudeNoseHooverIntegrator onReference(300, 20.0, 1, 40.0, 0.0005), onDevice(300, 20.0, 1, 40.0, 0.0005);
        vector<vector<Vec3> > positions;
        vector<double> baths, drudeTemperatures;
        vector<Vec3> velocities;
        for (MRattleDrudeNoseHooverIntegrator* integrator : {&onReference, &onDevice}) {
            integrator->setMaxDrudeDistance(0.02);
            std::unique_ptr<Context> context = (integrator == &onReference ? referenceContext(d, *integrator)
                                                : platformContext(d, *integrator, name, {{"Precision", "double"}}));
            if (velocities.empty()) {
                context->setVelocitiesToTemperature(300, 7);
                velocities = context->getState(State::Velocities).getVelocities();
            }
            context->setVelocities(velocities);
            integrator->step(25);
            positions.push_back(context->getState(State::Positions).getPositions());
            baths.push_back(integrator->computeHeatBathEnergy());
            drudeTemperatures.push_back(integrator->computeDrudeTemperature());
        }
        const double deviation = maxDeviation(positions[0], positions[1]);
        std::cout << name << ": " << numWaters << " Drude groups, after 25 steps " << deviation
                  << " nm from Reference; heat bath " << baths[1] << " kJ/mol (Reference's " << baths[0]
                  << "); Drude temperature " << drudeTemperatures[1] << " K (Reference's " << drudeTemperatures[0]
                  << ")" << std::endl;
        EXPECT_LT(deviation, 1e-7) << name;
        EXPECT_NEAR(baths[0], baths[1], 1e-6 * std::fabs(baths[0])) << name;
        EXPECT_GT(std::fabs(baths[0]), 1.0) << name;   // the chains moved
        EXPECT_NEAR(drudeTemperatures[0], drudeTemperatures[1], 1e-6 * drudeTemperatures[0]) << name;
    }
    // Device platforms only (Reference is the yardstick): a build or machine without one has nothing to compare.
    if (!any)
        GTEST_SKIP() << "no device platform here";
}

namespace {

/** 40 steps of the system on Reference and on a device platform (double), from the same velocities. */
template <class Integrator>
void followReference(const string& platformName, const DrudeSystem& d, const std::function<Integrator*()>& make,
                     const string& label) {
    vector<vector<Vec3> > positions;
    vector<double> baths;
    vector<Vec3> velocities;
    for (bool onDevice : {false, true}) {
        std::unique_ptr<Integrator> integrator(make());
        integrator->setMaxDrudeDistance(0.004);
        std::unique_ptr<Context> context = (onDevice ? platformContext(d, *integrator, platformName, {{"Precision", "double"}})
                                                     : referenceContext(d, *integrator));
        if (velocities.empty()) {
            context->setVelocitiesToTemperature(300, 7);
            velocities = context->getState(State::Velocities).getVelocities();
        }
        context->setVelocities(velocities);
        integrator->step(40);
        positions.push_back(context->getState(State::Positions).getPositions());
        if constexpr (std::is_same<Integrator, MRattleDrudeNoseHooverIntegrator>::value)
            baths.push_back(integrator->computeHeatBathEnergy());
    }
    const double deviation = maxDeviation(positions[0], positions[1]);
    std::cout << platformName << " " << label << ", Drude groups of 83 particles: after 40 steps " << deviation
              << " nm from Reference, bodies rigid to " << maxDistanceChange(d.positions, positions[1], d.bodies)
              << " nm, farthest Drude particle " << farthestDrude(d, positions[1]) << " nm" << std::endl;
    EXPECT_LT(deviation, 1e-7) << label;  // fixed-point device forces: 3e-8 measured
    EXPECT_GT(maxDeviation(d.positions, positions[0]), 1e-3) << "the bodies moved";
    EXPECT_LT(maxDistanceChange(d.positions, positions[1], d.bodies), 1e-11) << label;
    EXPECT_LE(farthestDrude(d, positions[1]), 0.004 * (1 + 1e-9)) << "the wall held the Drude particles";
    if (!baths.empty()) {
        std::cout << "  heat bath " << baths[1] << " kJ/mol (Reference's " << baths[0] << ")" << std::endl;
        EXPECT_NEAR(baths[0], baths[1], 1e-6 * std::fabs(baths[0])) << label;
        EXPECT_GT(std::fabs(baths[0]), 0.1) << "the chains moved";
    }
}

} // namespace

TEST(DrudeManyGroups, LargeBodiesDrudeGroupsFollowReference) {
    // Three 75-atom bodies, each with 8 Drude particles about 0.0045 nm off their cores (groups
    // of 83), beside 8 waters and 2 ions; a wall at 0.004 nm that acts from the first step.
    // Langevin at 0 K (friction and the wall's bounce, no noise) and Nose-Hoover.
    bool any = false;
    for (const string& name : devicePlatforms()) {
        if (!unavailable(name).empty())
            continue;
        any = true;
        DrudeSystem d = drudeWaters(8, 2, 0.34);
        addPolarizableBlobs(d, 3, 75);
        followReference<MRattleDrudeLangevinIntegrator>(
            name, d, [] { return new MRattleDrudeLangevinIntegrator(0, 5.0, 0, 20.0, 0.0005); }, "Langevin at 0 K");
        followReference<MRattleDrudeNoseHooverIntegrator>(
            name, d, [] { return new MRattleDrudeNoseHooverIntegrator(300, 20.0, 1, 40.0, 0.0005); }, "Nose-Hoover");
    }
    if (!any)
        GTEST_SKIP() << "no device platform here";
}

#else

TEST(DrudeManyGroups, NeedsOpenMMsDrudePlugin) {
    GTEST_SKIP() << "built without OpenMM's Drude plugin";
}

#endif
