/*
 * The kinetic energy split into the bodies' translation and rotation and the free particles,
 * with each part's degrees of freedom and temperature (RigidBodyIntegrator::
 * computeTranslationalTemperature() and the rest), on every platform and integrator.
 */
#include "MRattleLangevinIntegrator.h"
#include "TestSupport.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <gtest/gtest.h>
#include <cmath>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::vector;

namespace {

/**
 * Nonlinear bodies (the tetrahedral molecule), linear bodies (three collinear atoms of
 * different masses) and free atoms on a lattice, with no forces: the bodies are declared on
 * the integrator. Optionally a CMMotionRemover.
 */
struct Mixture {
    System system;
    vector<Vec3> positions;
    vector<vector<int> > bodies;
    int numNonlinear = 0, numLinear = 0, numFree = 0;
};

Mixture mixture(int nonlinear, int linear, int free, bool cmMotionRemover) {
    Mixture m;
    const Molecule t = tetrahedral();
    int site = 0;
    auto where = [&]() {
        const int n = 8;  // lattice of 8 x 8 x 8 cells, 1 nm apart
        const Vec3 cell(site % n, (site / n) % n, site / (n * n));
        site++;
        return cell * 1.0;
    };
    for (int b = 0; b < nonlinear; b++) {
        const Vec3 origin = where();
        const vector<Vec3> rotation = randomRotation(100 + b);
        vector<int> body;
        for (size_t i = 0; i < t.sites.size(); i++) {
            body.push_back(m.system.addParticle(t.masses[i]));
            m.positions.push_back(origin + rotate(rotation, t.sites[i]));
        }
        m.bodies.push_back(body);
    }
    const double linearMasses[] = {12.0, 16.0, 2.0};
    for (int b = 0; b < linear; b++) {
        const Vec3 origin = where();
        const Vec3 axis = rotate(randomRotation(500 + b), Vec3(1, 0, 0));
        vector<int> body;
        for (int i = 0; i < 3; i++) {
            body.push_back(m.system.addParticle(linearMasses[i]));
            m.positions.push_back(origin + axis * (0.11 * i));
        }
        m.bodies.push_back(body);
    }
    for (int i = 0; i < free; i++) {
        m.system.addParticle(i % 2 == 0 ? 39.948 : 4.0);
        m.positions.push_back(where());
    }
    if (cmMotionRemover)
        m.system.addForce(new CMMotionRemover());
    m.numNonlinear = nonlinear;
    m.numLinear = linear;
    m.numFree = free;
    return m;
}

/** One body, the tetrahedral molecule about the origin, in a System with no forces. */
Mixture oneBody() {
    return mixture(1, 0, 0, false);
}

double kineticEnergyOf(Context& context) {
    return context.getState(State::Energy).getKineticEnergy();
}

} // namespace

class KineticSplit : public RigidBodyTest {
protected:
    std::unique_ptr<RigidBodyIntegrator> integratorFor(const Mixture& m) const {
        std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
        for (const vector<int>& body : m.bodies)
            integrator->addRigidBody(body);
        return integrator;
    }
};

TEST_P(KineticSplit, DegreesOfFreedomSplitByKindAndAddUp) {
    for (bool remover : {false, true}) {
        Mixture m = mixture(4, 3, 5, remover);
        std::unique_ptr<RigidBodyIntegrator> integrator = integratorFor(m);
        std::unique_ptr<Context> context = makeContext(m.system, *integrator);
        context->setPositions(m.positions);
        // Linear bodies count 2 rotational degrees of freedom.
        EXPECT_EQ(3 * 4 + 2 * 3, integrator->getRotationalDegreesOfFreedom());
        double bodyMass = 0, freeMass = 0;
        for (int i = 0; i < m.system.getNumParticles(); i++)
            (i < (int) (4 * 5 + 3 * 3) ? bodyMass : freeMass) += m.system.getParticleMass(i);
        const double share = remover ? 3 * bodyMass / (bodyMass + freeMass) : 0;
        EXPECT_NEAR(3 * 7 - share, integrator->getTranslationalDegreesOfFreedom(), 1e-12);
        EXPECT_NEAR(3 * 5 - (remover ? 3 - share : 0), integrator->getFreeDegreesOfFreedom(), 1e-12);
        EXPECT_NEAR(integrator->getNumDegreesOfFreedom(),
                    integrator->getTranslationalDegreesOfFreedom() + integrator->getRotationalDegreesOfFreedom() +
                        integrator->getFreeDegreesOfFreedom(),
                    1e-12);
    }
}

TEST_P(KineticSplit, PartsAddUpToTheKineticEnergy) {
    Mixture m = mixture(6, 4, 5, false);
    std::unique_ptr<RigidBodyIntegrator> integrator = integratorFor(m);
    std::unique_ptr<Context> context = makeContext(m.system, *integrator);
    context->setPositions(m.positions);
    context->setVelocitiesToTemperature(300, 3);
    integrator->step(3);  // the Langevin integrator's noise changes them
    const double total = kineticEnergyOf(*context);
    const double translational = integrator->computeTranslationalKineticEnergy();
    const double rotational = integrator->computeRotationalKineticEnergy();
    const double free = integrator->computeFreeKineticEnergy();
    EXPECT_GT(translational, 0);
    EXPECT_GT(rotational, 0);
    EXPECT_GT(free, 0);
    EXPECT_NEAR(total, translational + rotational + free, 1e-10 * total);
    // Each part against the same formula on the host, from the State's velocities.
    const vector<Vec3> v = context->getState(State::Velocities).getVelocities();
    double hostTranslational = 0, hostFree = 0;
    for (const vector<int>& body : m.bodies) {
        Vec3 momentum;
        double mass = 0;
        for (int i : body) {
            momentum += v[i] * m.system.getParticleMass(i);
            mass += m.system.getParticleMass(i);
        }
        hostTranslational += 0.5 * momentum.dot(momentum) / mass;
    }
    for (int i = m.system.getNumParticles() - m.numFree; i < m.system.getNumParticles(); i++)
        hostFree += 0.5 * m.system.getParticleMass(i) * v[i].dot(v[i]);
    EXPECT_NEAR(hostTranslational, translational, 1e-10 * total);
    EXPECT_NEAR(hostFree, free, 1e-10 * total);
    EXPECT_NEAR(integrator->computeTranslationalTemperature(),
                2 * translational / (integrator->getTranslationalDegreesOfFreedom() * BOLTZ), 1e-9);
}

TEST_P(KineticSplit, ABodyRotatingInPlaceHasNoTranslationalTemperature) {
    Mixture m = oneBody();
    std::unique_ptr<RigidBodyIntegrator> integrator = integratorFor(m);
    std::unique_ptr<Context> context = makeContext(m.system, *integrator);
    context->setPositions(m.positions);
    const vector<double> mass = masses(m.system);
    Vec3 center;
    double total = 0;
    for (size_t i = 0; i < mass.size(); i++) {
        center += m.positions[i] * mass[i];
        total += mass[i];
    }
    center /= total;
    const Vec3 omega(3.0, -1.0, 2.0);  // rad/ps
    vector<Vec3> v(mass.size());
    double expected = 0;
    for (size_t i = 0; i < mass.size(); i++) {
        v[i] = omega.cross(m.positions[i] - center);
        expected += 0.5 * mass[i] * v[i].dot(v[i]);
    }
    context->setVelocities(v);
    EXPECT_NEAR(0.0, integrator->computeTranslationalKineticEnergy(), 1e-12 * expected);
    EXPECT_NEAR(0.0, integrator->computeTranslationalTemperature(), 1e-9);
    EXPECT_NEAR(expected, integrator->computeRotationalKineticEnergy(), 1e-10 * expected);
    EXPECT_NEAR(2 * expected / (3 * BOLTZ), integrator->computeRotationalTemperature(), 1e-8 * expected);
    EXPECT_EQ(0.0, integrator->computeFreeKineticEnergy());
}

TEST_P(KineticSplit, ABodyTranslatingWithoutTurningHasNoRotationalTemperature) {
    Mixture m = oneBody();
    std::unique_ptr<RigidBodyIntegrator> integrator = integratorFor(m);
    std::unique_ptr<Context> context = makeContext(m.system, *integrator);
    context->setPositions(m.positions);
    const vector<double> mass = masses(m.system);
    const Vec3 velocity(1.5, -0.5, 0.25);  // nm/ps
    double total = 0;
    for (double mi : mass)
        total += mi;
    context->setVelocities(vector<Vec3>(mass.size(), velocity));
    const double expected = 0.5 * total * velocity.dot(velocity);
    EXPECT_NEAR(expected, integrator->computeTranslationalKineticEnergy(), 1e-10 * expected);
    EXPECT_NEAR(0.0, integrator->computeRotationalKineticEnergy(), 1e-12 * expected);
    EXPECT_NEAR(0.0, integrator->computeRotationalTemperature(), 1e-9);
}

/**
 * setVelocitiesToTemperature draws Maxwell-Boltzmann velocities on the rigid degrees of
 * freedom (without centre-of-mass motion here: a CMMotionRemover) and scales them to exactly
 * 300 K: each part's temperature is then 300 K in expectation, if each part's degrees of
 * freedom are right (the linear bodies' 2, the CMMotionRemover's 3 shared by mass). The mean
 * over seeds is compared with 300 K within 4 standard errors of that mean.
 */
TEST_P(KineticSplit, EquipartitionByConstructionGivesEachPartTheTemperature) {
    Mixture m = mixture(60, 60, 60, true);
    std::unique_ptr<RigidBodyIntegrator> integrator = integratorFor(m);
    std::unique_ptr<Context> context = makeContext(m.system, *integrator);
    context->setPositions(m.positions);
    const int seeds = 12;
    vector<double> translational, rotational, free;
    for (int seed = 1; seed <= seeds; seed++) {
        context->setVelocitiesToTemperature(300, seed);
        translational.push_back(integrator->computeTranslationalTemperature());
        rotational.push_back(integrator->computeRotationalTemperature());
        free.push_back(integrator->computeFreeTemperature());
        EXPECT_NEAR(300, integrator->computeSystemTemperature(), 1e-6);
    }
    for (const vector<double>* series : {&translational, &rotational, &free}) {
        const double error = standardDeviation(*series) * std::sqrt(seeds / (seeds - 1.0)) / std::sqrt(seeds);
        EXPECT_GT(error, 0.5);   // a real spread: 180-360 degrees of freedom a part
        EXPECT_LT(error, 15.0);
        EXPECT_NEAR(300, mean(*series), 4 * error);
    }
}

TEST_P(KineticSplit, RefusedWithoutAContext) {
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.002);
    EXPECT_NE(std::string::npos, messageOf([&] { integrator->computeRotationalTemperature(); }).find("not bound"));
    EXPECT_NE(std::string::npos, messageOf([&] { integrator->getTranslationalDegreesOfFreedom(); }).find("not bound"));
}

INSTANTIATE_TEST_SUITE_P(Platforms, KineticSplit, ::testing::ValuesIn(allConfigs()), configName);
