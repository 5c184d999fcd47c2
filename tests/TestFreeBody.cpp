/*
 * A body with no external force: M-RATTLE is then the discrete Moser-Veselov map, which
 * conserves the energy and the space-frame angular momentum exactly, so both must hold to
 * round-off over long runs, also for an asymmetric top (three distinct moments).
 */
#include "TestSupport.h"
#include <gtest/gtest.h>
#include <cmath>
#include <iostream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::vector;

namespace {

struct Conservation {
    double energy, angularMomentum, rigidity, rotation;
};

/** One copy of the molecule (bonds only, at rest), random rigid velocities at 300 K, steps of 2 fs. */
Conservation runFreeBody(const Molecule& molecule, int steps, bool keepCenterOfMassMotion = false) {
    ClusterOptions options;
    options.nonbonded = false;
    Cluster c = buildCluster(molecule, 1, 1.0, 17, options);
    MRattleIntegrator integrator(0.002);
    Context context(*c.system, integrator, platform("Reference"));
    context.setPositions(c.positions);
    context.setVelocitiesToTemperature(300, 5);
    EXPECT_EQ(1, integrator.getNumBodiesInEffect());
    vector<double> m = masses(*c.system);
    // Keep the body at the origin: a body that drifts to |x| ~ 60 nm over the run loses
    // digits in every (x_new - x) / h and its momenta then wander at ~1e-6 relative.
    if (!keepCenterOfMassMotion) {
        vector<Vec3> v = context.getState(State::Velocities).getVelocities();
        double totalMass = 0;
        for (double mass : m)
            totalMass += mass;
        Vec3 centerVelocity = totalMomentum(m, v) / totalMass;
        for (Vec3& vi : v)
            vi -= centerVelocity;
        context.setVelocities(v);
    }
    State start = context.getState(State::Positions | State::Velocities | State::Energy);
    const double e0 = start.getKineticEnergy() + start.getPotentialEnergy();
    const Vec3 l0 = angularMomentum(m, start.getPositions(), start.getVelocities());
    Conservation result = {0, 0, 0, 0};
    const int chunk = 10000;
    for (int done = 0; done < steps; done += chunk) {
        integrator.step(chunk);
        State s = context.getState(State::Positions | State::Velocities | State::Energy);
        Vec3 dl = angularMomentum(m, s.getPositions(), s.getVelocities()) - l0;
        result.energy = std::max(result.energy, std::fabs(s.getKineticEnergy() + s.getPotentialEnergy() - e0) / e0);
        result.angularMomentum = std::max(result.angularMomentum, std::sqrt(dl.dot(dl) / l0.dot(l0)));
        result.rigidity = std::max(result.rigidity, maxDistanceChange(c.positions, s.getPositions(), c.molecules));
        result.rotation = std::max(result.rotation, maxDeviation(c.positions, s.getPositions()));
    }
    return result;
}

} // namespace

TEST(FreeBody, IsolatedBenzeneConservesEnergyAndAngularMomentum) {
    Conservation c = runFreeBody(benzene(), 100000);
    std::cout << "free benzene, 100,000 steps: energy " << c.energy << " relative, angular momentum "
              << c.angularMomentum << " relative, rigidity " << c.rigidity << " nm" << std::endl;
    EXPECT_GT(c.rotation, 0.05);  // it did turn
    EXPECT_LT(c.energy, 1e-10);
    EXPECT_LT(c.angularMomentum, 1e-10);
    EXPECT_LT(c.rigidity, 1e-11);
}

TEST(FreeBody, IsolatedAsymmetricTopConservesEnergyAndAngularMomentum) {
    Conservation c = runFreeBody(tetrahedral(), 100000);
    std::cout << "free asymmetric top, 100,000 steps: energy " << c.energy << " relative, angular momentum "
              << c.angularMomentum << " relative, rigidity " << c.rigidity << " nm" << std::endl;
    EXPECT_GT(c.rotation, 0.05);
    EXPECT_LT(c.energy, 1e-10);
    EXPECT_LT(c.angularMomentum, 1e-10);
    EXPECT_LT(c.rigidity, 1e-11);
}

TEST(FreeBody, DriftingBodyKeepsMomentaToLooserBound) {
    // With its centre-of-mass velocity the body drifts ~60 nm in 100,000 steps, and the
    // velocities derived from position differences lose digits with the distance from the
    // origin: measured 1e-9 to 4e-9 (energy) and 1e-6 to 9e-6 (angular momentum about the origin).
    Conservation c = runFreeBody(tetrahedral(), 100000, true);
    std::cout << "drifting asymmetric top, 100,000 steps: energy " << c.energy << " relative, angular momentum "
              << c.angularMomentum << " relative, rigidity " << c.rigidity << " nm" << std::endl;
    EXPECT_LT(c.energy, 1e-7);
    EXPECT_LT(c.angularMomentum, 1e-4);
    EXPECT_LT(c.rigidity, 1e-10);
}
