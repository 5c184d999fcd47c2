/*
 * Fuzz harness (issue 13): random body definitions, mutated integrator XML, damaged
 * checkpoints and random API call sequences, each case in a forked child so a crash is
 * counted, not fatal. Each category has an oracle:
 *   bodies       an independent check of the definition: invalid ones must be refused,
 *                valid ones accepted, and then stay rigid and finite for a few steps;
 *   xml          an accepted document must give an integrator with valid settings;
 *   checkpoints  any damage to the integrator's part must be refused;
 *   api          after any call sequence, a step that succeeds leaves finite positions
 *                and velocities;
 *   endforces    (issue 22) a body and free particles run into a wall where the forces
 *                stop being finite, with each integrator: a step that returns leaves a
 *                finite state, a refused one leaves the state exactly as it was;
 *   constraints  (issue 22) constrained free pairs with velocities up to 1000 nm/ps: a
 *                step that returns keeps every constraint, a refused one changes nothing;
 *   shapes       (issue 22) near-linear, tiny and near-coincident bodies at 300 K and
 *                2 fs: the degrees of freedom follow the documented shape rule (checked
 *                with the fuzzer's own moments), and linear and point bodies must step;
 *   xmldepth     (issue 22) integrator documents nested up to 200,000 deep or with
 *                elements inside <Particle>: refused if deeper than MaxXmlDepth or with
 *                a stray element, never a crash;
 *   drude        (issue 44, where OpenMM's Drude plugin is built) polarizable waters and
 *                an ion with a Drude integrator: a Drude particle in a body, a massless
 *                core or Drude particle, a bad temperature, friction or wall, a DrudeForce
 *                added after the Context must be refused; the rest steps and stays finite.
 * Every category that draws an integrator draws from the test registry (integrators()).
 * Reports per category: cases, accepted, refused, crashes, silent acceptances of wrong
 * input, wrong refusals of valid input. Exit status 1 if any crash, silent acceptance or
 * wrong refusal. Usage: FuzzMRattle [--cases N] [--seed S] [--only bodies,xml,...]
 * [--first K] [--verbose 1] (replay cases from K, printing each API call) [--selftest 1] (the first case of each category then crashes on purpose: the harness
 * must count it and fail).
 */
#include "MRattleBussiIntegrator.h"
#include "MRattleLangevinIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "internal/RigidBodyThermostats.h"
#include "MRattleXml.h"
#include "RigidSplittingIntegrator.h"
#include "mrattle/RigidBodyMath.h"
#include <Eigen/Eigenvalues>
#include "TestSupport.h"
#ifdef MRATTLE_HAVE_DRUDE
#include "DrudeTestSystem.h"
#include "MRattleDrudeLangevinIntegrator.h"
#include "MRattleDrudeNoseHooverIntegrator.h"
#endif
#include "openmm/serialization/XmlSerializer.h"
#include <csignal>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

bool verbose = false;
/** Data of a case's child (bytes): a damaged size that asks for more fails fast, as std::bad_alloc. */
const rlim_t ChildMemoryLimit = rlim_t(1) << 30;

enum Outcome { Accepted = 0, Refused = 1, SilentAcceptance = 3, WrongRefusal = 4, EmptyMessage = 5, OtherException = 6 };

/** 3 benzenes (0-35), a virtual site on atoms 0-2 (36), a massless particle (37); constraints 0-1 and 24-25. */
struct FuzzSystem {
    System system;
    vector<Vec3> positions;
    FuzzSystem() {
        Molecule b = benzene();
        HarmonicBondForce* bonds = new HarmonicBondForce();
        NonbondedForce* nonbonded = new NonbondedForce();
        for (int m = 0; m < 3; m++)
            for (size_t i = 0; i < b.sites.size(); i++) {
                system.addParticle(b.masses[i]);
                positions.push_back(b.sites[i] + Vec3(0.8 * m, 0, 0));
                nonbonded->addParticle(0, 0.3, 0.2);
            }
        for (int m = 0; m < 3; m++)
            for (auto& bond : b.bonds)
                bonds->addBond(12 * m + bond.first, 12 * m + bond.second, 0.14, 1000.0);
        system.addParticle(0.0);
        system.setVirtualSite(36, new ThreeParticleAverageSite(0, 1, 2, 0.3, 0.3, 0.4));
        positions.push_back(Vec3());
        system.addParticle(0.0);
        positions.push_back(Vec3(3, 3, 3));
        nonbonded->addParticle(0, 0.3, 0);
        nonbonded->addParticle(0, 0.3, 0);
        nonbonded->createExceptionsFromBonds({{0, 36}, {1, 36}, {2, 36}}, 0, 0);
        for (int m = 0; m < 3; m++)
            for (int i = 0; i < 12; i++)
                for (int j = i + 1; j < 12; j++)
                    nonbonded->addException(12 * m + i, 12 * m + j, 0, 1, 0, true);
        system.addForce(bonds);
        system.addForce(nonbonded);
        system.addConstraint(0, 1, (b.sites[1] - b.sites[0]).dot(b.sites[1] - b.sites[0]) > 0
                                        ? std::sqrt((b.sites[1] - b.sites[0]).dot(b.sites[1] - b.sites[0])) : 0.1);
        system.addConstraint(24, 25, std::sqrt((b.sites[1] - b.sites[0]).dot(b.sites[1] - b.sites[0])));
    }
};

bool allFinite(const vector<Vec3>& values) {
    for (const Vec3& v : values)
        if (!std::isfinite(v[0] + v[1] + v[2]))
            return false;
    return true;
}

/** Runs action; Refused on an OpenMMException with a message, else what action returns. */
int guarded(const std::function<int()>& action) {
    try {
        return action();
    } catch (const OpenMMException& e) {
        return std::strlen(e.what()) == 0 ? EmptyMessage : Refused;
    } catch (...) {
        return OtherException;
    }
}

// ---- bodies -------------------------------------------------------------------------------

int bodiesCase(std::mt19937& random) {
    FuzzSystem f;
    const int numParticles = f.system.getNumParticles();
    std::uniform_int_distribution<int> count(0, 4), size(0, 8), index(-2, numParticles + 2), coin(0, 9);
    vector<vector<int> > bodies(count(random));
    for (auto& body : bodies) {
        int n = size(random);
        for (int k = 0; k < n; k++)
            body.push_back(coin(random) < 7 ? std::uniform_int_distribution<int>(0, 35)(random) : index(random));
    }
    // The oracle, written independently of RigidBodyTopology.
    bool valid = true;
    std::map<int, int> owner;
    for (size_t b = 0; b < bodies.size(); b++) {
        if (bodies[b].empty())
            valid = false;
        for (int i : bodies[b]) {
            if (i < 0 || i >= numParticles || f.system.isVirtualSite(i) || f.system.getParticleMass(i) == 0)
                valid = false;
            else if (owner.count(i))
                valid = false;
            else
                owner[i] = b;
        }
    }
    auto bodyOf = [&](int i) {
        if (bodies.empty())
            return i < 36 ? i / 12 : -1;  // the molecules
        auto it = owner.find(i);
        return (it == owner.end() || bodies[it->second].size() < 2) ? -1 : it->second;
    };
    if (valid)
        for (int c = 0; c < f.system.getNumConstraints(); c++) {
            int p1, p2;
            double d;
            f.system.getConstraintParameters(c, p1, p2, d);
            if (bodyOf(p1) != bodyOf(p2))
                valid = false;
        }
    if (verbose)
        for (auto& body : bodies) {
            std::fprintf(stderr, "  body:");
            for (int i : body)
                std::fprintf(stderr, " %d", i);
            std::fprintf(stderr, "\n");
        }
    int outcome = guarded([&] {
        MRattleIntegrator integrator(0.001);
        for (auto& body : bodies)
            integrator.addRigidBody(body);
        Context context(f.system, integrator, platform("Reference"));
        context.setPositions(f.positions);
        // Bodies take their shape when positions are set (near-linear ones are put on their
        // axis, docs/ALGORITHM.md): rigid from there, and moved by little getting there.
        const vector<Vec3> set = context.getState(State::Positions).getPositions();
        for (int i = 0; i < f.system.getNumParticles(); i++)   // virtual sites are placed anew
            if (!f.system.isVirtualSite(i) && maxDeviation({f.positions[i]}, {set[i]}) > 0.01 * 2.5)
                return (int) SilentAcceptance;   // more than 1% of the largest possible body (2.5 nm)
        context.setVelocitiesToTemperature(300, 1);
        integrator.step(5);
        State s = context.getState(State::Positions | State::Velocities);
        if (!allFinite(s.getPositions()) || !allFinite(s.getVelocities()))
            return (int) SilentAcceptance;
        vector<vector<int> > rigid;
        for (auto& body : integrator.getBodiesInEffect())
            rigid.push_back(body);
        const double change = maxDistanceChange(set, s.getPositions(), rigid);
        if (verbose)
            std::fprintf(stderr, "  oracle: valid %d; largest change of an intra-body distance %g nm\n", (int) valid,
                         change);
        if (change > 1e-9)
            return (int) SilentAcceptance;
        return (int) Accepted;
    });
    if (outcome == Accepted && !valid)
        return SilentAcceptance;
    if (outcome == Refused && valid)
        return WrongRefusal;
    return outcome;
}

// ---- xml ------------------------------------------------------------------------------------

/** A document of MRattleIntegrator or, with settings of its own to damage, MRattleNoseHooverIntegrator. */
string baseXml(bool thermostat) {
    std::unique_ptr<RigidBodyIntegrator> integrator(thermostat ? (RigidBodyIntegrator*) new MRattleNoseHooverIntegrator(300, 10, 0.002, 4, 2, 5)
                                                               : (RigidBodyIntegrator*) new MRattleIntegrator(0.002));
    integrator->addRigidBody({0, 1, 2});
    integrator->addRigidBody({5, 7});
    std::stringstream stream;
    XmlSerializer::serialize<Integrator>(integrator.get(), "Integrator", stream);
    return stream.str();
}

/** Whether a deserialized Nose-Hoover integrator's own settings are ones its constructor accepts. */
bool validChainSettings(const MRattleNoseHooverIntegrator& chain) {
    return std::isfinite(chain.getTemperature()) && chain.getTemperature() > 0 &&
           std::isfinite(chain.getCollisionFrequency()) && chain.getCollisionFrequency() >= 0 &&
           chain.getChainLength() >= 1 && chain.getNumMultiTimeSteps() >= 1 &&
           RigidBodyThermostats::isSupportedYoshidaSuzukiOrder(chain.getNumYoshidaSuzukiTimeSteps());
}

int xmlCase(std::mt19937& random) {
    string xml = baseXml(std::uniform_int_distribution<int>(0, 1)(random) == 1);
    const char* tokens[] = {"0", "-1", "nan", "1e999", "0x10", "", "\"", "<", ">", "/>", "<Body size=\"1\">", "2.5", " a=\"1\""};
    std::uniform_int_distribution<int> ops(1, 3), kind(0, 5), byte(0, 255), token(0, 12);
    int n = ops(random);
    for (int k = 0; k < n && !xml.empty(); k++) {
        size_t at = std::uniform_int_distribution<size_t>(0, xml.size() - 1)(random);
        switch (kind(random)) {
        case 0: xml[at] = (char) byte(random); break;
        case 1: xml.erase(at, 1); break;
        case 2: xml.insert(at, 1, (char) byte(random)); break;
        case 3: xml.resize(at); break;
        case 4: xml.insert(at, tokens[token(random)]); break;
        default: {
            size_t length = std::uniform_int_distribution<size_t>(1, 40)(random);
            xml.insert(at, xml.substr(at, length));
        }
        }
    }
    return guarded([&] {
        std::unique_ptr<Integrator> integrator(deserializeIntegratorXml(xml));
        RigidBodyIntegrator* rigid = dynamic_cast<RigidBodyIntegrator*>(integrator.get());
        if (rigid == nullptr)
            return (int) Accepted;  // another integrator type (an edited type name): not ours to judge
        const double h = rigid->getStepSize(), tolerance = rigid->getConstraintTolerance();
        if (!std::isfinite(h) || h == 0 || !std::isfinite(tolerance) || !(tolerance > 0))
            return (int) SilentAcceptance;
        if (auto* chain = dynamic_cast<MRattleNoseHooverIntegrator*>(rigid))
            if (!validChainSettings(*chain))
                return (int) SilentAcceptance;
        for (int b = 0; b < rigid->getNumRigidBodies(); b++) {
            std::set<int> seen;
            for (int i : rigid->getRigidBodyParticles(b))
                if (i < 0 || !seen.insert(i).second)
                    return (int) SilentAcceptance;
            if (seen.empty())
                return (int) SilentAcceptance;
        }
        return (int) Accepted;
    });
}

// ---- checkpoints ----------------------------------------------------------------------------

/** One of the rigid-body integrators, drawn (every kernel's checkpoint state is fuzzed). */
std::unique_ptr<RigidBodyIntegrator> anyIntegrator(std::mt19937& random, double stepSize);

int checkpointCase(std::mt19937& random) {
    FuzzSystem f;
    f.system.addForce(new AndersenThermostat(300, 10.0));
    std::unique_ptr<RigidBodyIntegrator> drawn = anyIntegrator(random, 0.001);
    RigidBodyIntegrator& integrator = *drawn;
    Context context(f.system, integrator, platform("Reference"));
    context.setPositions(f.positions);
    context.setVelocitiesToTemperature(300, 2);
    integrator.step(3);
    std::stringstream stream;
    context.createCheckpoint(stream);
    string checkpoint = stream.str();
    const size_t start = checkpoint.rfind("MRattleC");
    std::uniform_int_distribution<size_t> where(start, checkpoint.size() - 1), anywhere(0, checkpoint.size() - 1);
    std::uniform_int_distribution<int> kind(0, 4), flips(1, 4), bit(0, 7);
    const State saved = context.getState(State::Positions | State::Velocities | State::Parameters);
    const int damage = kind(random);
    bool openMMPartDamaged = false;
    switch (damage) {
    case 0:
    case 1:
        for (int k = flips(random); k > 0; k--)
            checkpoint[where(random)] ^= (char) (1 << bit(random));
        break;
    case 2: checkpoint.resize(where(random)); break;
    case 3: checkpoint.insert(where(random), "junk"); break;
    default: {   // OpenMM's part too (issue 22)
        const size_t at = anywhere(random);
        openMMPartDamaged = at < start;
        checkpoint.insert(at, "junk");
        break;
    }
    }
    bool ours = false;   // refused by the integrator (OpenMM's own checks refuse before overwriting anything)
    int outcome = guarded([&] {
        std::istringstream in(checkpoint);
        try {
            context.loadCheckpoint(in);
        } catch (const OpenMMException& e) {
            ours = string(e.what()).find("OpenMM had already loaded") != string::npos;
            throw;
        } catch (const std::bad_alloc&) {
            // OpenMM's own reader (7.7) takes a damaged count in its part as a size and allocates
            // it: under the child's memory limit a refusal by OpenMM, before the plugin reads anything.
            if (!openMMPartDamaged)
                throw;
            return (int) Refused;
        }
        return (int) Accepted;
    });
    if (outcome == Accepted && checkpoint != stream.str())
        return SilentAcceptance;
    if (outcome == Refused && ours) {
        // Stepping must wait for Context::reinitialize(), setState() or not, and then work.
        context.setState(saved);
        int next = guarded([&] {
            integrator.step(1);
            return (int) Accepted;
        });
        if (next != Refused)
            return SilentAcceptance;
        context.reinitialize();
        context.setState(saved);
        if (guarded([&] {
                integrator.step(5);
                return (int) Accepted;
            }) != Accepted)
            return WrongRefusal;
    }
    return outcome;
}

// ---- api --------------------------------------------------------------------------------------

int apiCase(std::mt19937& random) {
    FuzzSystem f;
    std::uniform_int_distribution<int> op(0, 13), small(-3, 40), coin(0, 1);
    std::uniform_real_distribution<double> real(-5, 5);
    const double specials[] = {0.0, -0.001, 0.001, 0.002, 1.0, 1e9, NAN, INFINITY, -INFINITY};
    auto special = [&] { return specials[std::uniform_int_distribution<int>(0, 8)(random)]; };
    std::unique_ptr<RigidBodyIntegrator> integrator;
    if (coin(random))
        integrator.reset(new MRattleIntegrator(0.001));
    else
        integrator.reset(new RigidSplittingIntegrator(0.001));
    std::unique_ptr<Context> context;
    int refusals = 0;
    const int length = std::uniform_int_distribution<int>(3, 15)(random);
    for (int k = 0; k < length; k++) {
        const int which = op(random);
        int code = guarded([&] {
            if (verbose)
                std::fprintf(stderr, "  op %d\n", which);
            switch (which) {
            case 0: integrator->addRigidBody({small(random), small(random)}); break;
            case 1:
            case 2: context.reset(new Context(f.system, *integrator, platform("Reference"))); break;
            case 3: if (context) context->setPositions(f.positions); break;
            case 4: {
                if (!context) break;
                vector<Vec3> x = f.positions;
                x[std::uniform_int_distribution<int>(0, 37)(random)][0] = special();
                context->setPositions(x);
                break;
            }
            case 5: if (context) context->setVelocitiesToTemperature(special() * 300, 1); break;
            case 6: {
                if (!context) break;
                vector<Vec3> v(f.positions.size(), Vec3(real(random), real(random), special()));
                context->setVelocities(v);
                break;
            }
            case 7: integrator->setStepSize(special()); break;
            case 8: integrator->setConstraintTolerance(special()); break;
            case 9: {
                integrator->step(small(random));
                if (context) {
                    State s = context->getState(State::Positions | State::Velocities);
                    if (!allFinite(s.getPositions()) || !allFinite(s.getVelocities())) {
                        if (verbose)
                            for (size_t i = 0; i < s.getPositions().size(); i++)
                                if (!allFinite({s.getPositions()[i], s.getVelocities()[i]}))
                                    std::fprintf(stderr, "  particle %zu: x %g %g %g v %g %g %g\n", i,
                                                 s.getPositions()[i][0], s.getPositions()[i][1], s.getPositions()[i][2],
                                                 s.getVelocities()[i][0], s.getVelocities()[i][1], s.getVelocities()[i][2]);
                        return (int) SilentAcceptance;
                    }
                }
                break;
            }
            case 10: integrator->isBodyLinear(small(random)); break;
            case 11: integrator->getRigidBodyParticles(small(random)); break;
            case 12: {
                if (!context) break;
                std::istringstream garbage(string(64, (char) small(random)));
                context->loadCheckpoint(garbage);
                break;
            }
            default: if (context) context->getState(State::Energy | State::Forces); break;
            }
            return (int) Accepted;
        });
        if (verbose)
            std::fprintf(stderr, "  -> %d\n", code);
        if (code == SilentAcceptance || code == EmptyMessage || code == OtherException)
            return code;
        refusals += (code == Refused);
    }
    return refusals > 0 ? Refused : Accepted;
}

// ---- issue 22: end-of-step forces, free constraints, shapes, XML depth ----------------------

std::unique_ptr<RigidBodyIntegrator> anyIntegrator(std::mt19937& random, double stepSize) {
    const vector<IntegratorTraits>& all = integrators();
    const int drawn = std::uniform_int_distribution<int>(0, (int) all.size() - 1)(random);
    if (verbose)
        std::fprintf(stderr, "  integrator %s\n", all[drawn].name.c_str());
    return std::unique_ptr<RigidBodyIntegrator>(all[drawn].make(stepSize));
}

/**
 * Step one at a time: SilentAcceptance if a step returns with a state that fails the
 * check, or a refused step changed positions, velocities or the step count.
 */
int stepChecked(Context& context, Integrator& integrator, int steps, const std::function<bool(const State&)>& good) {
    int outcome = Accepted;
    for (int k = 0; k < steps; k++) {
        State before = context.getState(State::Positions | State::Velocities);
        try {
            integrator.step(1);
        } catch (const OpenMMException& e) {
            State after = context.getState(State::Positions | State::Velocities);
            for (size_t i = 0; i < before.getPositions().size(); i++)
                if (!(before.getPositions()[i] == after.getPositions()[i]) ||
                    !(before.getVelocities()[i] == after.getVelocities()[i]))
                    return SilentAcceptance;
            if (before.getStepCount() != after.getStepCount() || std::strlen(e.what()) == 0)
                return SilentAcceptance;
            outcome = Refused;
            continue;  // stepping again must be refused or succeed properly too
        }
        State after = context.getState(State::Positions | State::Velocities);
        if (!allFinite(after.getPositions()) || !allFinite(after.getVelocities()) || !good(after))
            return SilentAcceptance;
    }
    return outcome;
}

int endForcesCase(std::mt19937& random) {
    std::uniform_real_distribution<double> unit(0, 1);
    System system;
    // A 3-atom body (bonded: a molecule) and two free atoms; a wall sqrt(c - x) or log(c - x).
    for (double m : {16.0, 1.0, 1.0, 12.0, 40.0})
        system.addParticle(m);
    const double wallAt = 1.0 + 0.3 * unit(random);
    CustomExternalForce* wall = new CustomExternalForce(unit(random) < 0.5 ? "sqrt(c-x)" : "-log(c-x)");
    wall->addGlobalParameter("c", wallAt);
    for (int i = 0; i < 5; i++)
        if (unit(random) < 0.8)
            wall->addParticle(i, {});
    system.addForce(wall);
    HarmonicBondForce* bonds = new HarmonicBondForce();
    bonds->addBond(0, 1, 0.1, 1);
    bonds->addBond(0, 2, 0.1, 1);
    system.addForce(bonds);
    std::unique_ptr<RigidBodyIntegrator> integrator = anyIntegrator(random, 0.001 + 0.02 * unit(random));
    Context context(system, *integrator, platform(unit(random) < 0.5 ? "Reference" : "CPU"));
    vector<Vec3> x = {Vec3(0.9, 0, 0), Vec3(0.95, 0.08, 0), Vec3(0.85, 0, 0.1), Vec3(0.9, 1, 0), Vec3(0.9, 0, 1)};
    context.setPositions(x);
    const double speed = 20 * unit(random);
    vector<Vec3> v;
    for (int i = 0; i < 5; i++)
        v.push_back(Vec3(speed * (0.5 + unit(random)), speed * (unit(random) - 0.5), 0));
    context.setVelocities(v);
    return stepChecked(context, *integrator, 60, [](const State&) { return true; });
}

int constraintsCase(std::mt19937& random) {
    std::uniform_real_distribution<double> unit(0, 1);
    System system;
    for (double m : {12.0, 12.0, 1.0, 16.0, 16.0, 1.0, 1.0})
        system.addParticle(m);
    system.addConstraint(0, 1, 0.1);
    system.addConstraint(1, 2, 0.11);  // a chain 0-1-2 (CCMA) and a pair 3-4
    system.addConstraint(3, 4, 0.12);
    std::unique_ptr<RigidBodyIntegrator> free = anyIntegrator(random, 0.0005 + 0.01 * unit(random));
    free->addRigidBody({5, 6});  // the rest is free
    Context context(system, *free, platform(unit(random) < 0.5 ? "Reference" : "CPU"));
    vector<Vec3> x = {Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0.1, 0.11, 0), Vec3(1, 0, 0), Vec3(1.12, 0, 0),
                      Vec3(2, 0, 0), Vec3(2.1, 0, 0)};
    context.setPositions(x);
    const double speed = std::pow(10.0, 3 * unit(random));   // 1 to 1000 nm/ps
    vector<Vec3> v;
    for (int i = 0; i < 7; i++)
        v.push_back(Vec3(unit(random) - 0.5, unit(random) - 0.5, unit(random) - 0.5) * (2 * speed));
    context.setVelocities(v);
    const double tolerance = free->getConstraintTolerance();
    return stepChecked(context, *free, 5, [&](const State& state) {
        const vector<Vec3>& p = state.getPositions();
        for (int c = 0; c < system.getNumConstraints(); c++) {
            int a, b;
            double d;
            system.getConstraintParameters(c, a, b, d);
            const double length = std::sqrt((p[a] - p[b]).dot(p[a] - p[b]));
            if (!(std::fabs(length - d) <= 2 * tolerance * d))
                return false;
        }
        return true;
    });
}

int shapesCase(std::mt19937& random) {
    std::uniform_real_distribution<double> unit(0, 1);
    const int regime = std::uniform_int_distribution<int>(0, 3)(random);
    // 0: a 3-5 atom rod of normal size with one atom off its line (below the linear
    // threshold or clearly above it); 1: a tiny body; 2: a water with an atom 1e-6 nm from
    // its oxygen; 3: a rod bent anywhere between (may be refused: judged only for the rule).
    const int numAtoms = regime == 2 ? 4 : std::uniform_int_distribution<int>(3, 5)(random);
    vector<double> masses;
    vector<Vec3> sites;
    const double scale = regime == 1 ? std::pow(10.0, -9 + 5.5 * unit(random)) : 0.1 + 0.1 * unit(random);
    if (regime == 2) {
        masses = {16, 1, 1, 2};
        sites = {Vec3(0, 0, 0), Vec3(0.09572, 0, 0), Vec3(-0.024, 0.0927, 0), Vec3(1e-6, 0, 0)};
    }
    else {
        for (int k = 0; k < numAtoms; k++) {
            masses.push_back(1 + 30 * unit(random));
            sites.push_back(regime == 1 ? Vec3(unit(random), unit(random), unit(random)) * scale
                                        : Vec3(scale * (k - 0.5 * (numAtoms - 1)), 0, 0));
        }
        if (regime != 1) {
            const double offset = regime == 0 ? (unit(random) < 0.5 ? std::pow(10.0, -9 + 6 * unit(random))
                                                                     : scale * (0.1 + 0.2 * unit(random)))
                                              : scale * std::pow(10.0, -6 + 5.5 * unit(random));
            sites[std::uniform_int_distribution<int>(0, numAtoms - 1)(random)][1] += offset;
        }
    }
    // The fuzzer's own moments: the rule as docs/ALGORITHM.md states it.
    double total = 0;
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < sites.size(); k++) {
        total += masses[k];
        center += masses[k] * Eigen::Vector3d(sites[k][0], sites[k][1], sites[k][2]);
    }
    center /= total;
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    double rms2 = 0;
    for (size_t k = 0; k < sites.size(); k++) {
        Eigen::Vector3d a = Eigen::Vector3d(sites[k][0], sites[k][1], sites[k][2]) - center;
        inertia += masses[k] * (a.squaredNorm() * Eigen::Matrix3d::Identity() - a * a.transpose());
        rms2 += masses[k] * a.squaredNorm() / total;
    }
    const Eigen::Vector3d moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(inertia).eigenvalues();
    const double ratio = moments(0) / moments(2);
    const bool point = std::sqrt(rms2) <= RigidBodyMath::PointRadius;
    if (!point && std::fabs(std::log(ratio / RigidBodyMath::LinearMomentRatio)) < std::log(2.0))
        return Accepted;  // within a factor 2 of the threshold: round-off may decide either way
    const int expectedDof = point ? 3 : ratio <= RigidBodyMath::LinearMomentRatio ? 5 : 6;
    System system;
    vector<Vec3> positions;
    const Vec3 where(unit(random) * 3, unit(random) * 3, unit(random) * 3);
    vector<Vec3> rotation = randomRotation(random());
    vector<int> body;
    for (size_t k = 0; k < sites.size(); k++) {
        body.push_back(system.addParticle(masses[k]));
        positions.push_back(where + rotate(rotation, sites[k]));
    }
    std::unique_ptr<RigidBodyIntegrator> integrator = anyIntegrator(random, 0.002);
    integrator->addRigidBody(body);
    Context context(system, *integrator, platform(unit(random) < 0.5 ? "Reference" : "CPU"));
    context.setPositions(positions);
    if (integrator->getNumDegreesOfFreedom() != expectedDof) {
        if (verbose)
            std::fprintf(stderr, "  dof %d, expected %d (ratio %g, rms %g)\n", integrator->getNumDegreesOfFreedom(),
                         expectedDof, ratio, std::sqrt(rms2));
        return SilentAcceptance;
    }
    const vector<Vec3> start = context.getState(State::Positions).getPositions();
    context.setVelocitiesToTemperature(300, 1 + random() % 1000);
    const int outcome = stepChecked(context, *integrator, 40, [&](const State& state) {
        return maxDistanceChange(start, state.getPositions(), {body}) <= 1e-9 * (1 + scale);
    });
    if (outcome == Refused && (regime != 3 && expectedDof < 6))
        return WrongRefusal;  // linear and point bodies must step at 300 K and 2 fs
    if (outcome == Refused && regime == 2)
        return WrongRefusal;
    return outcome;
}

int xmlDepthCase(std::mt19937& random) {
    std::uniform_real_distribution<double> unit(0, 1);
    MRattleIntegrator original(0.002);
    original.addRigidBody({0, 1, 2});
    std::stringstream stream;
    XmlSerializer::serialize<Integrator>(&original, "Integrator", stream);
    string xml = stream.str();
    const int depth = (int) std::pow(10.0, 5.3 * unit(random));
    const char* names[] = {"a", "Particle", "Body", "RigidBodies", "Integrator"};
    const string name = names[std::uniform_int_distribution<int>(0, 4)(random)];
    string open, close;
    for (int k = 0; k < depth; k++) {
        open += "<" + name + ">";
        close += "</" + name + ">";   // all the same name: the order is that of nesting
    }
    // Inside a <Particle>, inside the root, or around the whole document.
    const int where = std::uniform_int_distribution<int>(0, 2)(random);
    // Every such document has an element where none belongs (or a root that is no
    // integrator): it must be refused, by the depth check or by the proxies.
    if (where == 0) {
        const size_t at = xml.find("<Particle index=\"1\"/>");
        xml.replace(at, string("<Particle index=\"1\"/>").size(), "<Particle index=\"1\">" + open + close + "</Particle>");
    }
    else if (where == 1)
        xml.insert(xml.find("<RigidBodies"), open + close);
    else {
        const size_t at = xml.find("<Integrator");
        xml = xml.substr(0, at) + open + xml.substr(at) + close;
    }
    int outcome = guarded([&] {
        delete deserializeIntegratorXml(xml);
        return (int) Accepted;
    });
    return outcome == Accepted ? (int) SilentAcceptance : outcome;
}

// ---- issue 44: Drude integrators ------------------------------------------------------------

#ifdef MRATTLE_HAVE_DRUDE
int drudeCase(std::mt19937& random) {
    Drude::DrudeSystem d = Drude::drudeWaters(2, 1, 0.4);
    std::uniform_int_distribution<int> coin(0, 5);
    const double good[] = {0.0, 1.0, 300.0}, bad[] = {-1.0, NAN, INFINITY, -INFINITY};
    bool valid = true;
    // One setting in six drawn bad; its setter must refuse it.
    auto setting = [&](double goodValue) {
        if (coin(random) > 0)
            return goodValue >= 0 ? goodValue : good[std::uniform_int_distribution<int>(0, 2)(random)];
        valid = false;
        return bad[std::uniform_int_distribution<int>(0, 3)(random)];
    };
    const bool nh = coin(random) < 3;
    const vector<double> settings = {setting(300), setting(-1), setting(1), setting(-1), setting(0.02)};
    const bool drudeInBody = coin(random) == 0, masslessCore = coin(random) == 0, addedLater = coin(random) == 0;
    valid &= !drudeInBody && !masslessCore && !addedLater;
    if (masslessCore)
        d.system.setParticleMass(coin(random) < 3 ? d.pairs[0].second : d.pairs[2].first, 0.0);
    if (addedLater)
        d.system.removeForce(1);
    if (verbose)
        std::fprintf(stderr, "  %s settings %g %g %g %g %g, Drude in body %d, massless %d, added later %d\n",
                     nh ? "NoseHoover" : "Langevin", settings[0], settings[1], settings[2], settings[3], settings[4],
                     drudeInBody, masslessCore, addedLater);
    int outcome = guarded([&] {
        std::unique_ptr<RigidBodyIntegrator> integrator;
        if (nh) {
            auto* made = new MRattleDrudeNoseHooverIntegrator(300, 10, 1, 20, 0.001);
            integrator.reset(made);
            made->setTemperature(settings[0]);
            made->setCollisionFrequency(settings[1]);
            made->setDrudeTemperature(settings[2]);
            made->setDrudeCollisionFrequency(settings[3]);
            made->setMaxDrudeDistance(settings[4]);
        } else {
            auto* made = new MRattleDrudeLangevinIntegrator(300, 1, 1, 20, 0.001);
            integrator.reset(made);
            made->setTemperature(settings[0]);
            made->setFriction(settings[1]);
            made->setDrudeTemperature(settings[2]);
            made->setDrudeFriction(settings[3]);
            made->setMaxDrudeDistance(settings[4]);
        }
        for (const vector<int>& body : d.bodies)
            integrator->addRigidBody(body);
        if (drudeInBody)
            integrator->addRigidBody({d.pairs[2].second, d.pairs[2].first});   // the ion and its Drude particle
        Context context(d.system, *integrator, platform(coin(random) < 3 ? "Reference" : "CPU"));
        context.setPositions(d.positions);
        context.setVelocitiesToTemperature(300, 1);
        if (addedLater) {
            DrudeForce* drude = new DrudeForce();
            for (const auto& pair : d.pairs)
                drude->addParticle(pair.first, pair.second, -1, -1, -1, -1.2, 0.001, 1.0, 1.0);
            d.system.addForce(drude);
        }
        integrator->step(5);
        const State s = context.getState(State::Positions | State::Velocities);
        return (int) (allFinite(s.getPositions()) && allFinite(s.getVelocities()) ? Accepted : SilentAcceptance);
    });
    if (valid && outcome == Refused)
        return WrongRefusal;
    return (!valid && outcome == Accepted) ? (int) SilentAcceptance : outcome;
}
#endif

struct Counts {
    int cases = 0, accepted = 0, refused = 0, crashes = 0, silent = 0, wrongRefusals = 0, emptyMessages = 0, other = 0;
};

} // namespace

int main(int argc, char** argv) {
    int cases = 50, first = 0;
    unsigned seed = 1;
    string only = "bodies,xml,checkpoints,api,endforces,constraints,shapes,xmldepth,drude";
    bool selftest = false;
    for (int i = 1; i + 1 < argc; i += 2) {
        string flag = argv[i];
        if (flag == "--cases")
            cases = std::atoi(argv[i + 1]);
        else if (flag == "--seed")
            seed = std::atoi(argv[i + 1]);
        else if (flag == "--only")
            only = argv[i + 1];
        else if (flag == "--first")
            first = std::atoi(argv[i + 1]);
        else if (flag == "--verbose")
            verbose = std::atoi(argv[i + 1]) != 0;
        else if (flag == "--selftest")
            selftest = std::atoi(argv[i + 1]) != 0;
    }
    loadPlugins();
    std::map<string, std::function<int(std::mt19937&)> > categories = {
        {"bodies", bodiesCase}, {"xml", xmlCase}, {"checkpoints", checkpointCase}, {"api", apiCase},
        {"endforces", endForcesCase}, {"constraints", constraintsCase}, {"shapes", shapesCase},
        {"xmldepth", xmlDepthCase}};
#ifdef MRATTLE_HAVE_DRUDE
    categories["drude"] = drudeCase;
#else
    std::printf("drude: not drawn (this build has no OpenMM Drude plugin)\n");
#endif
    bool clean = true;
    std::printf("%-12s %7s %9s %8s %8s %7s %15s %7s\n", "category", "cases", "accepted", "refused", "crashes", "silent",
                "wrong refusals", "other");
    for (const string name : {"bodies", "xml", "checkpoints", "api", "endforces", "constraints", "shapes", "xmldepth", "drude"}) {
        if (only.find(name) == string::npos || !categories.count(name))
            continue;
        Counts counts;
        for (int c = first; c < first + cases; c++) {
            pid_t child = fork();
            if (child == 0) {
                alarm(60);  // a hang counts as a crash
                const rlimit memory = {ChildMemoryLimit, ChildMemoryLimit};
                setrlimit(RLIMIT_DATA, &memory);
                if (selftest && c == 0)
                    std::raise(SIGSEGV);
                std::mt19937 random(seed * 1000003u + c * 7919u + std::hash<string>()(name));
                std::_Exit(categories.at(name)(random));
            }
            int status = 0;
            waitpid(child, &status, 0);
            counts.cases++;
            if (WIFSIGNALED(status)) {
                counts.crashes++;
                std::fprintf(stderr, "%s case %d (seed %u): killed by signal %d\n", name.c_str(), c, seed, WTERMSIG(status));
                continue;
            }
            switch (WEXITSTATUS(status)) {
            case Accepted: counts.accepted++; break;
            case Refused: counts.refused++; break;
            case SilentAcceptance:
                counts.silent++;
                std::fprintf(stderr, "%s case %d (seed %u): wrong input accepted\n", name.c_str(), c, seed);
                break;
            case WrongRefusal:
                counts.wrongRefusals++;
                std::fprintf(stderr, "%s case %d (seed %u): valid input refused\n", name.c_str(), c, seed);
                break;
            case EmptyMessage: counts.emptyMessages++; counts.other++; break;
            default: counts.other++; break;
            }
        }
        std::printf("%-12s %7d %9d %8d %8d %7d %15d %7d\n", name.c_str(), counts.cases, counts.accepted, counts.refused,
                    counts.crashes, counts.silent, counts.wrongRefusals, counts.other);
        clean &= counts.crashes == 0 && counts.silent == 0 && counts.wrongRefusals == 0 && counts.other == 0;
    }
    std::printf("%s\n", clean ? "fuzz: no crash, no silent acceptance, no wrong refusal"
                              : "fuzz: FAILED (see the cases above)");
    return clean ? 0 : 1;
}
