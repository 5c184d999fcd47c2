#include "TestSupport.h"
#include <gtest/gtest.h>
#include "openmm/reference/SimTKOpenMMRealType.h"

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;

TEST(Smoke, IsolatedBenzeneStaysRigid) {
    Molecule b = benzene();
    System system;
    for (double m : b.masses)
        system.addParticle(m);
    HarmonicBondForce* bonds = new HarmonicBondForce();
    for (auto& p : b.bonds)
        bonds->addBond(p.first, p.second, 0.14, 1000.0);
    system.addForce(bonds);
    MRattleIntegrator integrator(0.002);
    Context context(system, integrator, platform("Reference"));
    context.setPositions(b.sites);
    context.setVelocitiesToTemperature(300, 1);
    std::vector<Vec3> initial = context.getState(State::Positions).getPositions();
    double e0 = context.getState(State::Energy).getKineticEnergy();
    integrator.step(1000);
    State s = context.getState(State::Positions | State::Energy);
    EXPECT_EQ(1, integrator.getNumBodiesInEffect());
    EXPECT_EQ(6, integrator.getNumDegreesOfFreedom());
    EXPECT_LT(maxDistanceChange(initial, s.getPositions(), integrator.getBodiesInEffect()), 1e-12);
    EXPECT_NEAR(e0, s.getKineticEnergy(), 1e-10 * e0);
    EXPECT_NEAR(0.5 * 6 * BOLTZ * 300, e0, 1e-9);
}
