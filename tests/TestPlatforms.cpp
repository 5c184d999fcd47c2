/*
 * The CPU platform runs the same physics as Reference. Its nonbonded forces are single
 * precision, so trajectories part at round-off and drift apart; the test holds M-RATTLE's
 * CPU-vs-Reference difference to what OpenMM's own VerletIntegrator shows on the same
 * System from the same start.
 */
#include "TestSupport.h"
#include <gtest/gtest.h>
#include <iostream>
#include <map>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::vector;

namespace {


/** Positions after the steps from the given start, on one platform. */
vector<Vec3> finalPositions(const Cluster& c, Integrator& integrator, const std::string& platformName,
                            const State& start, int steps) {
    Context context(*c.system, integrator, platform(platformName), platformProperties(platformName));
    context.setPositions(start.getPositions());
    context.setVelocities(start.getVelocities());
    integrator.step(steps);
    return context.getState(State::Positions).getPositions();
}

} // namespace

TEST(Platforms, CpuAgreesWithReferenceAsVerletDoes) {
    Cluster c = buildCluster(benzene(), 2, 0.65, 4);
    const double stepSize = 0.001;
    const int steps = 200;
    // One rigid start for everything.
    MRattleIntegrator setup(stepSize);
    Context setupContext(*c.system, setup, platform("Reference"));
    setupContext.setPositions(c.positions);
    setupContext.setVelocitiesToTemperature(300, 2);
    State start = setupContext.getState(State::Positions | State::Velocities);

    MRattleIntegrator mrattleReference(stepSize), mrattleCpu(stepSize);
    vector<Vec3> a = finalPositions(c, mrattleReference, "Reference", start, steps);
    vector<Vec3> b = finalPositions(c, mrattleCpu, "CPU", start, steps);
    VerletIntegrator verletReference(stepSize), verletCpu(stepSize);
    vector<Vec3> va = finalPositions(c, verletReference, "Reference", start, steps);
    vector<Vec3> vb = finalPositions(c, verletCpu, "CPU", start, steps);
    const double mrattle = maxDeviation(a, b), verlet = maxDeviation(va, vb);
    std::cout << "CPU vs Reference after " << steps << " steps: M-RATTLE " << mrattle << " nm, VerletIntegrator "
              << verlet << " nm; M-RATTLE rigidity on CPU " << maxDistanceChange(start.getPositions(), b, c.molecules)
              << " nm" << std::endl;
    EXPECT_GT(maxDeviation(start.getPositions(), a), 1e-2);  // the molecules moved
    EXPECT_GT(mrattle, 0.0);  // the CPU platform's own forces were used
    EXPECT_LT(mrattle, 5 * verlet);
    EXPECT_LT(mrattle, 1e-4);
    EXPECT_LT(maxDistanceChange(start.getPositions(), b, c.molecules), 1e-12);
}

TEST(Platforms, CpuBodySemanticsMatchReference) {
    Cluster c = buildCluster(tetrahedral(), 2, 0.45, 5);
    c.system->addForce(new CMMotionRemover());
    for (const std::string name : {"Reference", "CPU"}) {
        MRattleIntegrator integrator(0.002);
        Context context(*c.system, integrator, platform(name), platformProperties(name));
        context.setPositions(c.positions);
        context.setVelocitiesToTemperature(300, 3);
        EXPECT_EQ(c.molecules, integrator.getBodiesInEffect());
        EXPECT_EQ(8 * 6 - 3, integrator.getNumDegreesOfFreedom());
        integrator.step(100);
        EXPECT_LT(maxDistanceChange(c.positions, context.getState(State::Positions).getPositions(), c.molecules), 1e-12);
    }
}
