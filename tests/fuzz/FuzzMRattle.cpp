/*
 * Fuzz harness (issue 13): random body definitions, mutated integrator XML, damaged
 * checkpoints and random API call sequences, each case in a forked child so a crash is
 * counted, not fatal. Each category has an oracle:
 *   bodies       an independent check of the definition: invalid ones must be refused,
 *                valid ones accepted, and then stay rigid and finite for a few steps;
 *   xml          an accepted document must give an integrator with valid settings;
 *   checkpoints  any damage to the integrator's part must be refused;
 *   api          after any call sequence, a step that succeeds leaves finite positions
 *                and velocities.
 * Reports per category: cases, accepted, refused, crashes, silent acceptances of wrong
 * input, wrong refusals of valid input. Exit status 1 if any crash, silent acceptance or
 * wrong refusal. Usage: FuzzMRattle [--cases N] [--seed S] [--only bodies,xml,...]
 * [--first K] [--verbose 1] (replay cases from K, printing each API call) [--selftest 1] (the first case of each category then crashes on purpose: the harness
 * must count it and fail).
 */
#include "MRattleXml.h"
#include "RigidSplittingIntegrator.h"
#include "TestSupport.h"
#include "openmm/serialization/XmlSerializer.h"
#include <csignal>
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
    int outcome = guarded([&] {
        MRattleIntegrator integrator(0.001);
        for (auto& body : bodies)
            integrator.addRigidBody(body);
        Context context(f.system, integrator, platform("Reference"));
        context.setPositions(f.positions);
        context.setVelocitiesToTemperature(300, 1);
        integrator.step(5);
        State s = context.getState(State::Positions | State::Velocities);
        if (!allFinite(s.getPositions()) || !allFinite(s.getVelocities()))
            return (int) SilentAcceptance;
        vector<vector<int> > rigid;
        for (auto& body : integrator.getBodiesInEffect())
            rigid.push_back(body);
        if (maxDistanceChange(f.positions, s.getPositions(), rigid) > 1e-9)
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

string baseXml() {
    MRattleIntegrator integrator(0.002);
    integrator.addRigidBody({0, 1, 2});
    integrator.addRigidBody({5, 7});
    std::stringstream stream;
    XmlSerializer::serialize<Integrator>(&integrator, "Integrator", stream);
    return stream.str();
}

int xmlCase(std::mt19937& random) {
    string xml = baseXml();
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

int checkpointCase(std::mt19937& random) {
    FuzzSystem f;
    f.system.addForce(new AndersenThermostat(300, 10.0));
    MRattleIntegrator integrator(0.001);
    Context context(f.system, integrator, platform("Reference"));
    context.setPositions(f.positions);
    context.setVelocitiesToTemperature(300, 2);
    integrator.step(3);
    std::stringstream stream;
    context.createCheckpoint(stream);
    string checkpoint = stream.str();
    const size_t start = checkpoint.rfind("MRattleC");
    std::uniform_int_distribution<size_t> where(start, checkpoint.size() - 1);
    std::uniform_int_distribution<int> kind(0, 3), flips(1, 4), bit(0, 7);
    switch (kind(random)) {
    case 0:
    case 1:
        for (int k = flips(random); k > 0; k--)
            checkpoint[where(random)] ^= (char) (1 << bit(random));
        break;
    case 2: checkpoint.resize(where(random)); break;
    default: checkpoint.insert(where(random), "junk"); break;
    }
    int outcome = guarded([&] {
        std::istringstream in(checkpoint);
        context.loadCheckpoint(in);
        return (int) Accepted;
    });
    if (outcome == Accepted && checkpoint != stream.str())
        return SilentAcceptance;
    if (outcome == Refused) {
        // Stepping must wait for new positions and velocities.
        int next = guarded([&] {
            integrator.step(1);
            return (int) Accepted;
        });
        if (next != Refused)
            return SilentAcceptance;
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

struct Counts {
    int cases = 0, accepted = 0, refused = 0, crashes = 0, silent = 0, wrongRefusals = 0, emptyMessages = 0, other = 0;
};

} // namespace

int main(int argc, char** argv) {
    int cases = 50, first = 0;
    unsigned seed = 1;
    string only = "bodies,xml,checkpoints,api";
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
    const std::map<string, std::function<int(std::mt19937&)> > categories = {
        {"bodies", bodiesCase}, {"xml", xmlCase}, {"checkpoints", checkpointCase}, {"api", apiCase}};
    bool clean = true;
    std::printf("%-12s %7s %9s %8s %8s %7s %15s %7s\n", "category", "cases", "accepted", "refused", "crashes", "silent",
                "wrong refusals", "other");
    for (const string name : {"bodies", "xml", "checkpoints", "api"}) {
        if (only.find(name) == string::npos)
            continue;
        Counts counts;
        for (int c = first; c < first + cases; c++) {
            pid_t child = fork();
            if (child == 0) {
                alarm(60);  // a hang counts as a crash
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
