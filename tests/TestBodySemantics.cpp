/*
 * What a rigid body is and how it mixes with the rest of a System: intra-body forces have
 * no effect; explicit bodies with free and constrained free particles; linear and
 * one-particle bodies; degrees of freedom and temperature; constraints inside bodies;
 * virtual sites; thermostat and barostat; integration force groups.
 *
 * A value-parameterised suite (BodySemantics) over every platform and rigid-body
 * integrator (allConfigs()): these are promises of every rigid-body integrator. The
 * comparison with RATTLE (an independent constrained solution of the same dynamics) is
 * M-RATTLE's own and stays a plain test on Reference.
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

const double ArgonMass = 39.948, ArgonSigma = 0.34, ArgonEpsilon = 0.996;

/** Adds argon atoms (free particles) at the given positions to a cluster, with LJ in its NonbondedForce. */
vector<int> addArgon(Cluster& c, const vector<Vec3>& where) {
    NonbondedForce* nonbonded = nullptr;
    for (int f = 0; f < c.system->getNumForces(); f++)
        if (auto* force = dynamic_cast<NonbondedForce*>(&c.system->getForce(f)))
            nonbonded = force;
    vector<int> atoms;
    for (const Vec3& x : where) {
        atoms.push_back(c.system->addParticle(ArgonMass));
        c.positions.push_back(x);
        nonbonded->addParticle(0.0, ArgonSigma, ArgonEpsilon);
    }
    return atoms;
}

/** Two bodies of the tetrahedral molecule with four argon atoms and a free pair joined by a constraint. */
struct MixedSystem {
    Cluster cluster;
    vector<int> argon, pair;
};

MixedSystem mixedSystem() {
    MixedSystem m;
    Cluster& c = m.cluster;
    c.system.reset(new System());
    Molecule t = tetrahedral();
    NonbondedForce* nonbonded = new NonbondedForce();
    HarmonicBondForce* bonds = new HarmonicBondForce();
    for (int copy = 0; copy < 2; copy++) {
        vector<Vec3> orientation = randomRotation(21 + copy);
        vector<int> members;
        for (size_t i = 0; i < t.sites.size(); i++) {
            members.push_back(c.system->addParticle(t.masses[i]));
            nonbonded->addParticle(t.charges[i], t.sigmas[i], t.epsilons[i]);
            c.positions.push_back(Vec3(0.45 * copy, 0, 0) + rotate(orientation, t.sites[i]));
        }
        for (auto& bond : t.bonds) {
            Vec3 d = t.sites[bond.first] - t.sites[bond.second];
            bonds->addBond(members[bond.first], members[bond.second], std::sqrt(d.dot(d)), 1e5);
        }
        for (size_t i = 0; i < members.size(); i++)
            for (size_t j = i + 1; j < members.size(); j++)
                nonbonded->addException(members[i], members[j], 0, 1, 0);
        c.molecules.push_back(members);
    }
    c.system->addForce(nonbonded);
    c.system->addForce(bonds);
    m.argon = addArgon(c, {Vec3(0.22, 0.4, 0.05), Vec3(0.2, -0.38, 0.1), Vec3(-0.4, 0.05, 0.0), Vec3(0.85, 0.1, -0.05)});
    // A free N2-like pair held at 0.11 nm by a constraint.
    for (const Vec3& x : {Vec3(0.2, 0.05, 0.4), Vec3(0.2, 0.05, 0.51)}) {
        m.pair.push_back(c.system->addParticle(14.007));
        c.positions.push_back(x);
        nonbonded->addParticle(0.0, 0.32, 0.3);
    }
    nonbonded->addException(m.pair[0], m.pair[1], 0, 1, 0);
    c.system->addConstraint(m.pair[0], m.pair[1], 0.11);
    return m;
}

class BodySemantics : public RigidBodyTest {};

void declareBodies(RigidBodyIntegrator& integrator, const vector<vector<int> >& bodies) {
    for (const vector<int>& body : bodies)
        integrator.addRigidBody(body);
}

double kineticTemperature(const Context& context, int dof) {
    return 2 * context.getState(State::Energy).getKineticEnergy() / (dof * BOLTZ);
}

} // namespace

TEST_P(BodySemantics, IntraBodyForcesChangeNothing) {
    Cluster plain = buildCluster(benzene(), 2, 0.65, 4);
    Cluster loaded = buildCluster(benzene(), 2, 0.65, 4);
    ASSERT_EQ(plain.positions, loaded.positions);
    // Strained bonds, angles and a Lennard-Jones term between every pair inside each molecule.
    HarmonicBondForce* bonds = new HarmonicBondForce();
    HarmonicAngleForce* angles = new HarmonicAngleForce();
    CustomBondForce* lj = new CustomBondForce("4*0.3*((0.25/r)^12-(0.25/r)^6)");
    for (const vector<int>& m : loaded.molecules) {
        for (int k = 0; k < 6; k++) {
            bonds->addBond(m[k], m[(k + 1) % 6], 0.9 * 0.1397, 2e5);
            angles->addAngle(m[k], m[(k + 1) % 6], m[(k + 2) % 6], 1.9, 500);
        }
        for (size_t i = 0; i < m.size(); i++)
            for (size_t j = i + 1; j < m.size(); j++)
                lj->addBond(m[i], m[j]);
    }
    loaded.system->addForce(bonds);
    loaded.system->addForce(angles);
    loaded.system->addForce(lj);

    std::unique_ptr<RigidBodyIntegrator> a = makeIntegrator(0.002), b = makeIntegrator(0.002);
    std::unique_ptr<Context> plainContext = makeContext(*plain.system, *a);
    std::unique_ptr<Context> loadedContext = makeContext(*loaded.system, *b);
    plainContext->setPositions(plain.positions);
    plainContext->setVelocitiesToTemperature(300, 8);
    loadedContext->setPositions(plain.positions);
    loadedContext->setVelocities(plainContext->getState(State::Velocities).getVelocities());
    // The intra-body forces are large: the test is not vacuous.
    vector<Vec3> f = loadedContext->getState(State::Forces).getForces();
    EXPECT_GT(std::sqrt(f[0].dot(f[0])), 1e3);
    // One step from the same state: the intra-body forces cancel to round-off.
    a->step(1);
    b->step(1);
    double firstStep = maxDeviation(plainContext->getState(State::Positions).getPositions(),
                                    loadedContext->getState(State::Positions).getPositions());
    EXPECT_LT(firstStep, 1e-14);
    a->step(499);
    b->step(499);
    vector<Vec3> x1 = plainContext->getState(State::Positions).getPositions();
    const double deviation = maxDeviation(x1, loadedContext->getState(State::Positions).getPositions());
    const double motion = maxDeviation(plain.positions, x1);
    std::cout << "intra-body forces: position difference after 1 step " << firstStep << " nm, after 500 steps "
              << deviation << " nm, atoms moved " << motion << " nm" << std::endl;
    EXPECT_GT(motion, 1e-2);
    // Later steps leave round-off each step too (of the bodies' forces, over 1e3 kJ/mol/nm:
    // ~1e-7 relative where a platform sums forces in single precision), which chaos grows by
    // a factor that depends on the trajectory (measured 1e-12 to 4e-9 nm over the platforms
    // and integrators). A leak of these forces into the motion would grow like the motion.
    EXPECT_LT(deviation, 1e-4 * motion);
}

TEST_P(BodySemantics, ExplicitBodiesWithFreeParticles) {
    SKIP_UNLESS_CONSERVES_ENERGY(GetParam());
    // Declared bodies, free atoms and a constrained free pair: what is rigid, what is free,
    // the degrees of freedom and the temperature they give; then the bodies stay rigid
    // and the pair keeps its length while the system moves.
    MixedSystem m = mixedSystem();
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    integrator->setConstraintTolerance(1e-12);
    declareBodies(*integrator, m.cluster.molecules);
    std::unique_ptr<Context> context = makeContext(*m.cluster.system, *integrator);
    context->setPositions(m.cluster.positions);
    context->setVelocitiesToTemperature(300, 2);
    EXPECT_EQ(m.cluster.molecules, integrator->getBodiesInEffect());
    vector<int> expectedFree = m.argon;
    expectedFree.insert(expectedFree.end(), m.pair.begin(), m.pair.end());
    EXPECT_EQ(expectedFree, integrator->getFreeParticles());
    EXPECT_EQ(2 * 6 + 6 * 3 - 1, integrator->getNumDegreesOfFreedom());
    EXPECT_NEAR(300, kineticTemperature(*context, integrator->getNumDegreesOfFreedom()), 1e-9);
    integrator->step(200);
    vector<Vec3> x = context->getState(State::Positions).getPositions();
    EXPECT_GT(maxDeviation(m.cluster.positions, x), 1e-2);
    EXPECT_LT(maxDistanceChange(m.cluster.positions, x, m.cluster.molecules), 1e-10);
    Vec3 d = x[m.pair[0]] - x[m.pair[1]];
    EXPECT_NEAR(0.11, std::sqrt(d.dot(d)), 1e-11);
}

// M-RATTLE's own: the same trajectory as RATTLE with the bodies written as constraints.
TEST(MRattleBodySemantics, ExplicitBodiesWithFreeParticlesFollowRattle) {
    MixedSystem m = mixedSystem();
    System& system = *m.cluster.system;
    MRattleIntegrator integrator(0.002);
    integrator.setConstraintTolerance(1e-12);
    declareBodies(integrator, m.cluster.molecules);
    // The reference: CCMA with 9 constraints per body (all pairs but sites 1-2) and the pair's constraint.
    System referenceSystem;
    for (int i = 0; i < system.getNumParticles(); i++)
        referenceSystem.addParticle(system.getParticleMass(i));
    for (int f = 0; f < system.getNumForces(); f++)
        referenceSystem.addForce(XmlSerializer::clone<Force>(system.getForce(f)));
    referenceSystem.addConstraint(m.pair[0], m.pair[1], 0.11);
    for (const vector<int>& body : m.cluster.molecules)
        for (size_t i = 0; i < body.size(); i++)
            for (size_t j = i + 1; j < body.size(); j++)
                if (!(i == 1 && j == 2)) {
                    Vec3 d = m.cluster.positions[body[i]] - m.cluster.positions[body[j]];
                    referenceSystem.addConstraint(body[i], body[j], std::sqrt(d.dot(d)));
                }
    Context context(system, integrator, platform("Reference"));
    context.setPositions(m.cluster.positions);
    context.setVelocitiesToTemperature(300, 2);
    EXPECT_EQ(m.cluster.molecules, integrator.getBodiesInEffect());
    vector<int> expectedFree = m.argon;
    expectedFree.insert(expectedFree.end(), m.pair.begin(), m.pair.end());
    EXPECT_EQ(expectedFree, integrator.getFreeParticles());
    EXPECT_EQ(2 * 6 + 6 * 3 - 1, integrator.getNumDegreesOfFreedom());
    EXPECT_NEAR(300, kineticTemperature(context, integrator.getNumDegreesOfFreedom()), 1e-9);

    CustomIntegrator* rattle = rattleVerletIntegrator(0.002, 1e-12);
    Context rattleContext(referenceSystem, *rattle, platform("Reference"));
    State start = context.getState(State::Positions | State::Velocities);
    rattleContext.setPositions(start.getPositions());
    rattleContext.setVelocities(start.getVelocities());
    integrator.step(200);
    rattle->step(200);
    vector<Vec3> x1 = context.getState(State::Positions).getPositions();
    vector<Vec3> x2 = rattleContext.getState(State::Positions).getPositions();
    delete rattle;
    double deviation = maxDeviation(x1, x2);
    std::cout << "bodies + free atoms + constrained pair vs RATTLE after 200 steps: " << deviation << " nm" << std::endl;
    EXPECT_GT(maxDeviation(start.getPositions(), x1), 1e-2);
    EXPECT_LT(deviation, 1e-9);
    Vec3 d = x1[m.pair[0]] - x1[m.pair[1]];
    EXPECT_NEAR(0.11, std::sqrt(d.dot(d)), 1e-11);
}

TEST_P(BodySemantics, FreeConstraintHeldAtTolerance) {
    MixedSystem m = mixedSystem();
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    integrator->setConstraintTolerance(1e-6);
    declareBodies(*integrator, m.cluster.molecules);
    std::unique_ptr<Context> context = makeContext(*m.cluster.system, *integrator);
    context->setPositions(m.cluster.positions);
    context->setVelocitiesToTemperature(300, 4);
    double worst = 0;
    for (int chunk = 0; chunk < 10; chunk++) {
        integrator->step(100);
        State s = context->getState(State::Positions | State::Velocities);
        Vec3 d = s.getPositions()[m.pair[0]] - s.getPositions()[m.pair[1]];
        worst = std::max(worst, std::fabs(std::sqrt(d.dot(d)) - 0.11) / 0.11);
        // Velocities along the constraint vanish at the same tolerance.
        Vec3 dv = s.getVelocities()[m.pair[0]] - s.getVelocities()[m.pair[1]];
        EXPECT_LT(std::fabs(dv.dot(d)) / d.dot(d), 1e-4);
    }
    std::cout << "free constraint at tolerance 1e-6: largest relative distance error " << worst << std::endl;
    EXPECT_LT(worst, 2e-6);
}

TEST_P(BodySemantics, MoleculesAreBodiesInAutomaticMode) {
    MixedSystem m = mixedSystem();
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = makeContext(*m.cluster.system, *integrator);
    context->setPositions(m.cluster.positions);
    // The two molecules and the constrained pair (a two-particle linear body); argon is free.
    vector<vector<int> > expected = m.cluster.molecules;
    expected.push_back(m.pair);
    EXPECT_EQ(expected, integrator->getBodiesInEffect());
    EXPECT_EQ(m.argon, integrator->getFreeParticles());
    EXPECT_FALSE(integrator->isBodyLinear(0));
    EXPECT_TRUE(integrator->isBodyLinear(2));
    // A constrained free pair (3 + 3 - 1) and a linear body (5) have the same count.
    EXPECT_EQ(2 * 6 + 5 + 4 * 3, integrator->getNumDegreesOfFreedom());
    EXPECT_EQ(0, integrator->getTopology().getFreeConstraints().size());
    EXPECT_EQ(1, integrator->getTopology().getNumIgnoredConstraints());
}

TEST_P(BodySemantics, LinearBodyStaysLinearWithoutSpin) {
    SKIP_UNLESS_CONSERVES_ENERGY(GetParam());
    // O=C=S (distinct masses) among argon atoms.
    Molecule ocs;
    ocs.sites = {Vec3(-0.116, 0, 0), Vec3(0, 0, 0), Vec3(0.156, 0, 0)};
    ocs.masses = {15.999, 12.011, 32.06};
    ocs.charges = {0, 0, 0};
    ocs.sigmas = {0.3, 0.33, 0.36};
    ocs.epsilons = {0.6, 0.4, 1.0};
    ocs.bonds = {{0, 1}, {1, 2}};
    Cluster c = buildCluster(ocs, 1, 1.0, 12);
    vector<int> argon = addArgon(c, {Vec3(0.3, 0.25, 0), Vec3(-0.3, -0.25, 0.1), Vec3(0.05, 0.1, 0.36), Vec3(0.1, -0.35, -0.2)});
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = makeContext(*c.system, *integrator);
    context->setPositions(c.positions);
    context->setVelocitiesToTemperature(300, 6);
    ASSERT_EQ(1, integrator->getNumBodiesInEffect());
    EXPECT_TRUE(integrator->isBodyLinear(0));
    EXPECT_EQ(5 + 4 * 3, integrator->getNumDegreesOfFreedom());
    EXPECT_NEAR(300, kineticTemperature(*context, integrator->getNumDegreesOfFreedom()), 1e-9);
    vector<double> m = masses(*c.system);
    Vec3 axis0 = c.positions[2] - c.positions[0];
    axis0 /= std::sqrt(axis0.dot(axis0));
    double worstLinearity = 0, worstSpin = 0;
    vector<Vec3> x;
    for (int chunk = 0; chunk < 10; chunk++) {
        integrator->step(100);
        State s = context->getState(State::Positions | State::Velocities);
        x = s.getPositions();
        const vector<Vec3>& v = s.getVelocities();
        Vec3 e = x[2] - x[0], f = x[1] - x[0];
        worstLinearity = std::max(worstLinearity, std::sqrt(e.cross(f).dot(e.cross(f)) / (e.dot(e) * f.dot(f))));
        // Angular momentum of the body about its centre, along its axis.
        double mass = m[0] + m[1] + m[2];
        Vec3 center = (x[0] * m[0] + x[1] * m[1] + x[2] * m[2]) / mass;
        Vec3 velocity = (v[0] * m[0] + v[1] * m[1] + v[2] * m[2]) / mass;
        Vec3 l;
        for (int i = 0; i < 3; i++)
            l += (x[i] - center).cross(v[i] - velocity) * m[i];
        e /= std::sqrt(e.dot(e));
        worstSpin = std::max(worstSpin, std::fabs(l.dot(e)) / std::sqrt(l.dot(l)));
    }
    Vec3 axis = x[2] - x[0];
    axis /= std::sqrt(axis.dot(axis));
    std::cout << "linear body: non-collinearity " << worstLinearity << ", spin about axis " << worstSpin
              << " of |L|, axis turned by " << std::acos(axis.dot(axis0)) << " rad" << std::endl;
    EXPECT_GT(std::acos(axis.dot(axis0)), 0.05);  // it turned
    EXPECT_LT(maxDistanceChange(c.positions, x, c.molecules), 1e-11);
    EXPECT_LT(worstLinearity, 1e-11);
    EXPECT_LT(worstSpin, 1e-11);
}

TEST_P(BodySemantics, SingleParticleBodyIsFree) {
    MixedSystem m = mixedSystem();
    std::unique_ptr<RigidBodyIntegrator> withSingle = makeIntegrator(0.002), without = makeIntegrator(0.002);
    declareBodies(*withSingle, m.cluster.molecules);
    declareBodies(*without, m.cluster.molecules);
    withSingle->addRigidBody({m.argon[1]});
    std::unique_ptr<Context> a = makeContext(*m.cluster.system, *withSingle);
    std::unique_ptr<Context> b = makeContext(*m.cluster.system, *without);
    EXPECT_EQ(3, withSingle->getNumRigidBodies());
    EXPECT_EQ(2, withSingle->getNumBodiesInEffect());
    EXPECT_EQ(without->getFreeParticles(), withSingle->getFreeParticles());
    EXPECT_EQ(without->getNumDegreesOfFreedom(), withSingle->getNumDegreesOfFreedom());
    a->setPositions(m.cluster.positions);
    b->setPositions(m.cluster.positions);
    a->setVelocitiesToTemperature(300, 3);
    // Both Contexts receive the same velocities through the same path (setVelocities
    // projects them, which is idempotent only to round-off).
    std::vector<Vec3> velocities = a->getState(State::Velocities).getVelocities();
    a->setVelocities(velocities);
    b->setVelocities(velocities);
    withSingle->step(100);
    without->step(100);
    EXPECT_EQ(0.0, maxDeviation(a->getState(State::Positions).getPositions(), b->getState(State::Positions).getPositions()));
}

TEST_P(BodySemantics, TemperatureAndDegreesOfFreedomWithMotionRemover) {
    SKIP_UNLESS_CONSERVES_ENERGY(GetParam());
    MixedSystem m = mixedSystem();
    m.cluster.system->addForce(new CMMotionRemover(1));
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    declareBodies(*integrator, m.cluster.molecules);
    std::unique_ptr<Context> context = makeContext(*m.cluster.system, *integrator);
    context->setPositions(m.cluster.positions);
    EXPECT_EQ(2 * 6 + 6 * 3 - 1 - 3, integrator->getNumDegreesOfFreedom());
    for (double temperature : {10.0, 300.0, 1000.0}) {
        context->setVelocitiesToTemperature(temperature, 9);
        EXPECT_NEAR(temperature, kineticTemperature(*context, integrator->getNumDegreesOfFreedom()), 1e-10 * temperature);
        Vec3 p = totalMomentum(masses(*m.cluster.system), context->getState(State::Velocities).getVelocities());
        EXPECT_LT(std::sqrt(p.dot(p)), 1e-10);
    }
    // A cluster with nothing free: 27 benzenes, 27 * 6 - 3.
    Cluster c = buildCluster(benzene(), 3, 0.65, 1);
    c.system->addForce(new CMMotionRemover());
    std::unique_ptr<RigidBodyIntegrator> clusterIntegrator = makeIntegrator(0.002);
    std::unique_ptr<Context> clusterContext = makeContext(*c.system, *clusterIntegrator);
    clusterContext->setPositions(c.positions);
    clusterContext->setVelocitiesToTemperature(250, 1);
    EXPECT_EQ(27 * 6 - 3, clusterIntegrator->getNumDegreesOfFreedom());
    EXPECT_NEAR(250, kineticTemperature(*clusterContext, 27 * 6 - 3), 1e-9);
}

TEST_P(BodySemantics, KineticEnergyFromTemperatureIsExact) {
    // setVelocitiesToTemperature() gives rigid velocities whose kinetic energy is exactly
    // dof * kT / 2: two bond-only benzenes (molecules as bodies), 12 degrees of freedom.
    Molecule mol = benzene();
    System system;
    for (int copy = 0; copy < 2; copy++)
        for (double m : mol.masses)
            system.addParticle(m);
    HarmonicBondForce* bonds = new HarmonicBondForce();
    vector<Vec3> positions;
    for (int copy = 0; copy < 2; copy++) {
        for (auto& p : mol.bonds)
            bonds->addBond(p.first + 12 * copy, p.second + 12 * copy, 0.14, 1000.0);
        for (const Vec3& s : mol.sites)
            positions.push_back(s + Vec3(0, 0, 0.4 * copy));
    }
    system.addForce(bonds);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    std::unique_ptr<Context> context = makeContext(system, *integrator);
    context->setPositions(positions);
    EXPECT_EQ(2, integrator->getNumBodiesInEffect());
    EXPECT_EQ(12, integrator->getNumDegreesOfFreedom());
    context->setVelocitiesToTemperature(250, 4);
    EXPECT_NEAR(0.5 * 12 * BOLTZ * 250, context->getState(State::Energy).getKineticEnergy(), 1e-9);
    // The velocities are rigid: every intra-body distance is constant to first order.
    vector<Vec3> v = context->getState(State::Velocities).getVelocities();
    for (const vector<int>& body : integrator->getBodiesInEffect())
        for (int i : body)
            for (int j : body)
                EXPECT_NEAR(0.0, (positions[i] - positions[j]).dot(v[i] - v[j]), 1e-12);
    // Bond-only molecules: the intra-body forces do nothing, so the motion is free and rigid.
    integrator->step(300);
    vector<Vec3> x = context->getState(State::Positions).getPositions();
    EXPECT_GT(maxDeviation(positions, x), 1e-2);
    EXPECT_LT(maxDistanceChange(positions, x, integrator->getBodiesInEffect()), 1e-10);
}

TEST_P(BodySemantics, ClusterStaysRigidOverLongRuns) {
    // 8 declared asymmetric bodies (three distinct principal moments) with LJ and charges
    // between them: every intra-body distance is kept to round-off over 2000 steps, and
    // the velocities stay rigid.
    Cluster c = buildCluster(tetrahedral(), 2, 0.45, 7);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    declareBodies(*integrator, c.molecules);
    std::unique_ptr<Context> context = makeContext(*c.system, *integrator);
    context->setPositions(c.positions);
    context->setVelocitiesToTemperature(300, 3);
    EXPECT_EQ(c.molecules, integrator->getBodiesInEffect());
    EXPECT_EQ(8 * 6, integrator->getNumDegreesOfFreedom());
    integrator->step(2000);
    State s = context->getState(State::Positions | State::Velocities);
    const vector<Vec3>& x = s.getPositions();
    const vector<Vec3>& v = s.getVelocities();
    EXPECT_GT(maxDeviation(c.positions, x), 1e-2);
    EXPECT_LT(maxDistanceChange(c.positions, x, c.molecules), 1e-10);
    for (const vector<int>& body : c.molecules)
        for (int i : body)
            for (int j : body)
                EXPECT_NEAR(0.0, (x[i] - x[j]).dot(v[i] - v[j]), 1e-10);
}

TEST_P(BodySemantics, ConstraintsInsideBodiesAreIgnored) {
    Cluster plain = buildCluster(tetrahedral(), 2, 0.45, 5);
    Cluster constrained = buildCluster(tetrahedral(), 2, 0.45, 5);
    // All 10 pairs of every body: redundant (OpenMM's CCMA cannot solve them) and ignored.
    for (const vector<int>& m : constrained.molecules)
        for (size_t i = 0; i < m.size(); i++)
            for (size_t j = i + 1; j < m.size(); j++) {
                Vec3 d = constrained.positions[m[i]] - constrained.positions[m[j]];
                constrained.system->addConstraint(m[i], m[j], std::sqrt(d.dot(d)));
            }
    std::unique_ptr<RigidBodyIntegrator> a = makeIntegrator(0.002), b = makeIntegrator(0.002);
    std::unique_ptr<Context> plainContext = makeContext(*plain.system, *a);
    std::unique_ptr<Context> constrainedContext = makeContext(*constrained.system, *b);
    EXPECT_EQ(80, b->getTopology().getNumIgnoredConstraints());
    EXPECT_EQ(a->getNumDegreesOfFreedom(), b->getNumDegreesOfFreedom());
    EXPECT_EQ(a->getBodiesInEffect(), b->getBodiesInEffect());
    plainContext->setPositions(plain.positions);
    constrainedContext->setPositions(plain.positions);
    plainContext->setVelocitiesToTemperature(300, 1);
    constrainedContext->setVelocitiesToTemperature(300, 1);
    a->step(200);
    b->step(200);
    State s1 = plainContext->getState(State::Positions | State::Velocities);
    State s2 = constrainedContext->getState(State::Positions | State::Velocities);
    EXPECT_GT(maxDeviation(plain.positions, s1.getPositions()), 1e-2);
    // Exact on Reference and CPU. On OpenCL, OpenMM's own constraint algorithm, which
    // setVelocitiesToTemperature() applies to every System constraint, leaves round-off.
    const bool exact = (GetParam().platform == "Reference" || GetParam().platform == "CPU");
    EXPECT_LE(maxDeviation(s1.getPositions(), s2.getPositions()), exact ? 0.0 : 1e-10);
    EXPECT_LE(maxDeviation(s1.getVelocities(), s2.getVelocities()), exact ? 0.0 : 1e-9);
}

INSTANTIATE_TEST_SUITE_P(AllConfigs, BodySemantics, ::testing::ValuesIn(allConfigs()), configName);
