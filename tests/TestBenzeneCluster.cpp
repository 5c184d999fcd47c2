/*
 * 27 rigid benzenes (324 sites, planar bodies that distance constraints cannot hold) in
 * vacuum with LJ and charges between molecules: rigidity, second-order energy error and
 * no energy drift. Reference platform (double precision, deterministic); the cluster's
 * 14,000 steps take about 35 s there on a busy 2-core machine.
 */
#include "TestSupport.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <gtest/gtest.h>
#include <cmath>
#include <iostream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::vector;

namespace {

Cluster benzeneCluster() {
    ClusterOptions options;
    options.minSiteDistance = 0.25;
    return buildCluster(benzene(), 3, 0.65, 1, options);
}

struct Trajectory {
    vector<double> totalEnergy;  // sampled every sampleInterval ps
    double rigidity;             // largest change of an intra-body distance at the samples
    double kineticEnergy;
};

/** Runs the cluster from the same start at 250 K and records the total energy every sampleInterval ps. */
Trajectory runCluster(const Cluster& c, double stepSize, double duration, double sampleInterval) {
    MRattleIntegrator integrator(stepSize);
    Context context(*c.system, integrator, platform("Reference"));
    context.setPositions(c.positions);
    context.setVelocitiesToTemperature(250, 3);
    EXPECT_EQ(27, integrator.getNumBodiesInEffect());
    const int stepsPerSample = (int) std::lround(sampleInterval / stepSize);
    const int samples = (int) std::lround(duration / sampleInterval);
    Trajectory result;
    result.rigidity = 0;
    for (int s = 0; s <= samples; s++) {
        if (s > 0)
            integrator.step(stepsPerSample);
        State state = context.getState(State::Energy | State::Positions);
        result.totalEnergy.push_back(state.getKineticEnergy() + state.getPotentialEnergy());
        result.rigidity = std::max(result.rigidity, maxDistanceChange(c.positions, state.getPositions(), c.molecules));
        result.kineticEnergy = state.getKineticEnergy();
    }
    return result;
}

} // namespace

TEST(BenzeneCluster, RigidSecondOrderAndNoDrift) {
    Cluster c = benzeneCluster();
    ASSERT_EQ(324, c.system->getNumParticles());
    const double sampleInterval = 0.02;
    // 10,000 steps of 2 fs (20 ps).
    Trajectory coarse = runCluster(c, 0.002, 20.0, sampleInterval);
    // 4 ps at 1 fs, compared with the first 4 ps of the 2 fs run (the same start).
    Trajectory fine = runCluster(c, 0.001, 4.0, sampleInterval);
    vector<double> coarseStart(coarse.totalEnergy.begin(), coarse.totalEnergy.begin() + fine.totalEnergy.size());
    const double fluctuationCoarse = standardDeviation(coarseStart), fluctuationFine = standardDeviation(fine.totalEnergy);
    const double ratio = fluctuationCoarse / fluctuationFine;

    // Drift: the change of the least-squares line over the 20 ps, against the fluctuation.
    const double fluctuation = standardDeviation(coarse.totalEnergy);
    const double drift = linearSlope(coarse.totalEnergy) * (coarse.totalEnergy.size() - 1);
    std::cout << "27 benzene: rigidity " << coarse.rigidity << " nm (2 fs), " << fine.rigidity
              << " nm (1 fs); energy std over 4 ps " << fluctuationCoarse << " (2 fs) " << fluctuationFine
              << " (1 fs) kJ/mol, ratio " << ratio << "; over 20 ps std " << fluctuation << " kJ/mol, drift " << drift
              << " kJ/mol; final kinetic energy " << coarse.kineticEnergy << " kJ/mol" << std::endl;
    EXPECT_LT(coarse.rigidity, 1e-10);
    EXPECT_LT(fine.rigidity, 1e-10);
    EXPECT_NEAR(4.0, ratio, 0.8);
    // The fluctuation itself is small: below 1e-4 of the initial kinetic energy (162 DOF at 250 K).
    EXPECT_LT(fluctuation, 1e-4 * 0.5 * 162 * BOLTZ * 250);
    EXPECT_LT(std::fabs(drift), fluctuation);
}
