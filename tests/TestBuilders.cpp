/*
 * The shared test fixtures (TestSupport) build what they claim: molecules of the right
 * geometry, clusters without overlaps that OpenMM sees as separate molecules.
 */
#include "TestSupport.h"
#include <gtest/gtest.h>
#include <cmath>

using namespace OpenMM;
using namespace MRattleTest;
using std::vector;

namespace {

double distance(const Vec3& a, const Vec3& b) {
    Vec3 d = a - b;
    return std::sqrt(d.dot(d));
}

} // namespace

TEST(Builders, MoleculeGeometry) {
    Molecule b = benzene();
    ASSERT_EQ(12u, b.sites.size());
    EXPECT_NEAR(0.1397, distance(b.sites[0], b.sites[1]), 1e-12);
    EXPECT_NEAR(0.1084, distance(b.sites[0], b.sites[6]), 1e-12);
    Molecule w = water();
    EXPECT_NEAR(0.09572, distance(w.sites[0], w.sites[1]), 1e-12);
    EXPECT_NEAR(0.09572, distance(w.sites[0], w.sites[2]), 1e-12);
    Vec3 a = w.sites[1] - w.sites[0], c = w.sites[2] - w.sites[0];
    EXPECT_NEAR(104.52, std::acos(a.dot(c) / (a.dot(a))) * 180 / M_PI, 1e-9);
    Molecule t = tetrahedral();
    ASSERT_EQ(5u, t.sites.size());
    EXPECT_NEAR(0.177, distance(t.sites[0], t.sites[4]), 1e-12);
    // Non-planar: the four outer sites span a volume.
    Vec3 e1 = t.sites[2] - t.sites[1], e2 = t.sites[3] - t.sites[1], e3 = t.sites[4] - t.sites[1];
    EXPECT_GT(std::fabs(e1.dot(e2.cross(e3))), 1e-4);
    Vec3 center;
    for (size_t i = 0; i < t.sites.size(); i++)
        center += t.sites[i] * t.masses[i];
    EXPECT_LT(std::sqrt(center.dot(center)), 1e-12);
}

TEST(Builders, RandomRotationIsProper) {
    vector<Vec3> r = randomRotation(7);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            EXPECT_NEAR(i == j ? 1.0 : 0.0, r[i].dot(r[j]), 1e-14);
    EXPECT_NEAR(1.0, r[0].dot(r[1].cross(r[2])), 1e-14);
}

TEST(Builders, ClusterHasSeparateRigidMoleculesWithoutOverlaps) {
    Molecule b = benzene();
    ClusterOptions options;
    options.minSiteDistance = 0.25;
    Cluster c = buildCluster(b, 2, 0.65, 3, options);
    ASSERT_EQ(96, c.system->getNumParticles());
    ASSERT_EQ(8u, c.molecules.size());
    for (size_t m = 0; m < c.molecules.size(); m++) {
        for (size_t n = m + 1; n < c.molecules.size(); n++)
            for (int i : c.molecules[m])
                for (int j : c.molecules[n])
                    EXPECT_GE(distance(c.positions[i], c.positions[j]), 0.25);
        // Each copy is the molecule moved rigidly.
        EXPECT_NEAR(0.1397, distance(c.positions[c.molecules[m][2]], c.positions[c.molecules[m][3]]), 1e-12);
    }
    MRattlePlugin::MRattleIntegrator integrator(0.001);
    Context context(*c.system, integrator, platform("Reference"));
    context.setPositions(c.positions);
    EXPECT_EQ(c.molecules, integrator.getBodiesInEffect());
    // Bonds are at rest and all intramolecular nonbonded pairs are excluded: a lone molecule has zero energy.
    Cluster single = buildCluster(b, 1, 1.0, 3);
    VerletIntegrator verlet(0.001);
    Context lone(*single.system, verlet, platform("Reference"));
    lone.setPositions(single.positions);
    EXPECT_NEAR(0.0, lone.getState(State::Energy).getPotentialEnergy(), 1e-12);
}
