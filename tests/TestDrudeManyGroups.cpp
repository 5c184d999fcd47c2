/*
 * MRattleDrudeNoseHooverIntegrator on the device platforms with more Drude groups than one
 * work group holds (300 polarizable waters): the Drude groups' relative kinetic energy is
 * summed by every work group and the partial sums added by the chains' kernel, so the step
 * (double precision) follows Reference's and both chains move as on Reference.
 */
#include "DrudeTestSystem.h"
#include "MRattleDrudeNoseHooverIntegrator.h"
#include "TestSupport.h"
#include <gtest/gtest.h>
#include <cmath>
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

#else

TEST(DrudeManyGroups, NeedsOpenMMsDrudePlugin) {
    GTEST_SKIP() << "built without OpenMM's Drude plugin";
}

#endif
