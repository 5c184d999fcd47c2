// step_cost: wall-clock time of one integration step with forces excluded (the only force a zero
// CustomExternalForce), for N rigid bodies of k atoms on Reference and CPU: M-RATTLE and the splitting
// method against OpenMM's Verlet, SETTLE and CCMA, in interleaved batches so that ratios share the
// machine's load. Integrators, options and output: docs/benchmarks-cpp.md. Exit 2: a run diverged.
#include "BenchmarkSupport.h"
#include "MRattleBuildInfo.h"
#include "MRattleIntegrator.h"
#include "OpenMM.h"
#include "RigidSplittingIntegrator.h"
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <map>
#include <set>
#include <memory>
#include <string>
#include <vector>

extern "C" void registerMRattleReferenceKernelFactories();

using namespace OpenMM;
using std::string;
using std::vector;
using namespace MRattleBenchmark;

namespace {

/** A rigid body shape: sites (nm) about the centre of mass, and masses (amu). */
struct Shape {
    vector<std::array<double, 3> > sites;
    vector<double> masses;
};

/**
 * A non-planar, non-linear body of k atoms. k = 5 is a tetrahedral CX4 (methane-like,
 * C-H 0.109 nm); k = 3 is a bent triatomic; otherwise k atoms on a helix of radius
 * 0.15-0.3 nm with mixed masses (an irregular, asymmetric body).
 */
Shape bodyShape(int k) {
    Shape shape;
    if (k == 5) {
        const double s = 0.109 / std::sqrt(3.0);
        shape.sites = {{0, 0, 0}, {s, s, s}, {s, -s, -s}, {-s, s, -s}, {-s, -s, s}};
        shape.masses = {12.011, 1.008, 1.008, 1.008, 1.008};
    } else if (k == 3) {
        shape.sites = {{0, 0, 0}, {0.09572, 0, 0}, {-0.02399, 0.09267, 0}};
        shape.masses = {15.999, 1.008, 1.008};
    } else {
        const double massCycle[3] = {12.011, 1.008, 15.999};
        for (int j = 0; j < k; j++) {
            double radius = 0.15 + 0.15 * ((j * 7) % 5) / 4.0;
            double angle = 2.4 * j, z = -0.3 + 0.6 * j / (k > 1 ? k - 1 : 1);
            shape.sites.push_back({radius * std::cos(angle), radius * std::sin(angle), z});
            shape.masses.push_back(massCycle[j % 3]);
        }
    }
    double total = 0, center[3] = {0, 0, 0};
    for (int j = 0; j < k; j++) {
        total += shape.masses[j];
        for (int d = 0; d < 3; d++)
            center[d] += shape.masses[j] * shape.sites[j][d];
    }
    for (auto& site : shape.sites)
        for (int d = 0; d < 3; d++)
            site[d] -= center[d] / total;
    return shape;
}

struct Options {
    string out, ratios;
    vector<string> platforms = {"Reference", "CPU"};
    vector<int> bodies = {100, 300, 1000, 3000};
    vector<int> atoms = {3, 5, 12, 30};
    vector<string> integrators;  // empty: all
    int repeats = 7;
    double batchSeconds = 0.05;
    vector<int> threads = {1};
};

Options parse(int argc, char** argv) {
    Options options;
    for (int i = 1; i < argc; i++) {
        string flag = argv[i];
        if (i + 1 >= argc)
            throw std::runtime_error("step_cost: " + flag + " needs a value");
        string value = argv[++i];
        if (flag == "--out")
            options.out = value;
        else if (flag == "--ratios")
            options.ratios = value;
        else if (flag == "--platforms")
            options.platforms = split(value);
        else if (flag == "--bodies")
            options.bodies = splitInts(value);
        else if (flag == "--atoms")
            options.atoms = splitInts(value);
        else if (flag == "--repeats")
            options.repeats = std::stoi(value);
        else if (flag == "--batch-seconds")
            options.batchSeconds = std::stod(value);
        else if (flag == "--integrators")
            options.integrators = split(value);
        else if (flag == "--threads")
            options.threads = splitInts(value);
        else
            throw std::runtime_error("step_cost: unknown option " + flag);
    }
    if (options.repeats < 1 || options.batchSeconds <= 0)
        throw std::runtime_error("step_cost: --repeats must be >= 1 and --batch-seconds > 0");
    if (options.threads.empty() || *std::min_element(options.threads.begin(), options.threads.end()) < 1)
        throw std::runtime_error("step_cost: --threads needs counts >= 1");
    return options;
}

/** Pair constraints of one body: none, 9 of 10 (tetrahedron, for CCMA) or all pairs. */
enum class Pairs { None, Rigidifying, All };

struct Variant {
    string name;
    Pairs pairs;
};

/** One configuration being timed: its own System, Integrator and Context. */
struct Run {
    string name;
    int threads = 1;
    int constraintsPerBody = 0;
    std::unique_ptr<System> system;
    std::unique_ptr<Integrator> integrator;
    std::unique_ptr<Context> context;
    vector<double> secondsPerStep;
};

/**
 * OpenMM's CCMA couples two constraints that share an atom through the angle between
 * them, which it takes from a closing constraint or else from a HarmonicAngleForce; with
 * neither it diverges (NaN in the first step for the 9-constraint tetrahedron). So give it
 * every such angle, with zero force constant, in force group 1, which the integrator is
 * told not to evaluate: the angles inform CCMA and cost nothing per step.
 */
void addConstraintAngles(System& system, const Shape& shape, int numBodies) {
    const int k = shape.masses.size();
    std::set<std::pair<int, int> > constrained;
    for (int c = 0; c < system.getNumConstraints() && c < numBodies * k * k; c++) {
        int p1, p2;
        double distance;
        system.getConstraintParameters(c, p1, p2, distance);
        if (p1 >= k)
            break;  // every body is constrained alike: the first one tells which pairs
        constrained.insert({std::min(p1, p2), std::max(p1, p2)});
    }
    auto isConstrained = [&](int i, int j) { return constrained.count({std::min(i, j), std::max(i, j)}) > 0; };
    auto site = [&](int i) { return Vec3(shape.sites[i][0], shape.sites[i][1], shape.sites[i][2]); };
    HarmonicAngleForce* angles = new HarmonicAngleForce();
    for (int b = 0; b < numBodies; b++)
        for (int center = 0; center < k; center++)
            for (int i = 0; i < k; i++)
                for (int j = i + 1; j < k; j++) {
                    if (i == center || j == center || !isConstrained(i, center) || !isConstrained(j, center) ||
                        isConstrained(i, j))
                        continue;
                    Vec3 u = site(i) - site(center), w = site(j) - site(center);
                    double angle = std::acos(u.dot(w) / std::sqrt(u.dot(u) * w.dot(w)));
                    angles->addAngle(b * k + i, b * k + center, b * k + j, angle, 0.0);
                }
    angles->setForceGroup(1);
    system.addForce(angles);
}

std::unique_ptr<System> buildSystem(int numBodies, const Shape& shape, Pairs pairs,
                                    int& constraintsPerBody) {
    std::unique_ptr<System> system(new System());
    const int k = shape.masses.size();
    constraintsPerBody = 0;
    for (int b = 0; b < numBodies; b++) {
        const int first = system->getNumParticles();
        for (double m : shape.masses)
            system->addParticle(m);
        int count = 0;
        for (int i = 0; i < k; i++)
            for (int j = i + 1; j < k; j++) {
                // Rigidifying: every pair of the tetrahedron but the first H-H (atoms 1-2).
                bool keep = (pairs == Pairs::All) || (pairs == Pairs::Rigidifying && !(i == 1 && j == 2));
                if (!keep)
                    continue;
                double d2 = 0;
                for (int c = 0; c < 3; c++)
                    d2 += (shape.sites[i][c] - shape.sites[j][c]) * (shape.sites[i][c] - shape.sites[j][c]);
                system->addConstraint(first + i, first + j, std::sqrt(d2));
                count++;
            }
        constraintsPerBody = count;
    }
    if (pairs == Pairs::Rigidifying)
        addConstraintAngles(*system, shape, numBodies);
    CustomExternalForce* negligible = new CustomExternalForce("0*x");
    negligible->addParticle(0);
    system->addForce(negligible);
    return system;
}

vector<Vec3> buildPositions(int numBodies, const Shape& shape) {
    // Bodies on a cubic lattice 1.2 nm apart (they never interact).
    int side = 1;
    while (side * side * side < numBodies)
        side++;
    vector<Vec3> positions;
    for (int b = 0; b < numBodies; b++) {
        Vec3 center(1.2 * (b % side), 1.2 * ((b / side) % side), 1.2 * (b / (side * side)));
        for (const auto& site : shape.sites)
            positions.push_back(center + Vec3(site[0], site[1], site[2]));
    }
    return positions;
}

double secondsFor(Integrator& integrator, int steps) {
    Clock::time_point start = Clock::now();
    integrator.step(steps);
    return secondsSince(start);
}

} // namespace

int main(int argc, char** argv) {
    try {
        Options options = parse(argc, argv);
        bool allFinite = true;
        // The platform plugins of the OpenMM this was built against, unless the user names others.
        setenv("OPENMM_PLUGIN_DIR", MRATTLE_OPENMM_PLUGIN_DIR, 0);
        Platform::loadPluginsFromDirectory(Platform::getDefaultPluginsDirectory());
        registerMRattleReferenceKernelFactories();
        CsvOutputs csv(options.out, options.ratios);
        std::ostream& out = csv.out;
        std::ostream& ratios = csv.ratios;
        out << "platform,integrator,atoms_per_body,bodies,atoms,constraints_per_body,steps_per_batch,batches,"
               "median_us_per_step,min_us_per_step,max_us_per_step,median_ns_per_atom_step,finite,threads\n";
        ratios << "platform,atoms_per_body,bodies,ratio,value,target,met\n";
        for (const string& platformName : options.platforms) {
            Platform& platform = Platform::getPlatformByName(platformName);
            // Thread counts to run: only the CPU platform has any to choose.
            const vector<int> threadCounts = platformName == "CPU" ? options.threads : vector<int>{1};
            for (int k : options.atoms) {
                Shape shape = bodyShape(k);
                vector<Variant> variants = {{"verlet", Pairs::None}, {"mrattle", Pairs::None}, {"splitting", Pairs::None}};
                if (k == 5) {
                    variants.push_back({"mrattle_allpairs", Pairs::All});
                    variants.push_back({"verlet_ccma", Pairs::Rigidifying});
                }
                if (k == 3)
                    variants.push_back({"verlet_settle", Pairs::All});
                if (!options.integrators.empty())
                    variants.erase(std::remove_if(variants.begin(), variants.end(),
                                                  [&](const Variant& v) {
                                                      return std::find(options.integrators.begin(),
                                                                       options.integrators.end(),
                                                                       v.name) == options.integrators.end();
                                                  }),
                                   variants.end());
                for (int numBodies : options.bodies) {
                    vector<Vec3> positions = buildPositions(numBodies, shape);
                    vector<Run> runs;
                    for (int threads : threadCounts)
                    for (const Variant& variant : variants) {
                        if (threads != threadCounts[0] && variant.name != "verlet" && variant.name != "mrattle" &&
                            variant.name != "splitting")
                            continue;
                        Run run;
                        run.name = variant.name;
                        run.threads = threads;
                        std::map<string, string> properties;
                        if (platformName == "CPU")
                            properties["Threads"] = std::to_string(threads);
                        run.system = buildSystem(numBodies, shape, variant.pairs, run.constraintsPerBody);
                        if (variant.name.rfind("verlet", 0) == 0) {
                            run.integrator.reset(new VerletIntegrator(0.002));
                            run.integrator->setIntegrationForceGroups(1 << 0);
                        }
                        else {
                            MRattlePlugin::RigidBodyIntegrator* rigid =
                                (variant.name == "splitting")
                                    ? (MRattlePlugin::RigidBodyIntegrator*) new MRattlePlugin::RigidSplittingIntegrator(0.002)
                                    : (MRattlePlugin::RigidBodyIntegrator*) new MRattlePlugin::MRattleIntegrator(0.002);
                            for (int b = 0; b < numBodies; b++) {
                                vector<int> body;
                                for (int j = 0; j < k; j++)
                                    body.push_back(b * k + j);
                                rigid->addRigidBody(body);
                            }
                            run.integrator.reset(rigid);
                        }
                        run.context.reset(new Context(*run.system, *run.integrator, platform, properties));
                        run.context->setPositions(positions);
                        run.context->setVelocitiesToTemperature(300, 1);
                        runs.push_back(std::move(run));
                    }
                    // Warm up, then size the batches so each takes about batchSeconds.
                    vector<int> steps;
                    for (Run& run : runs) {
                        run.integrator->step(5);
                        double perStep = secondsFor(*run.integrator, 10) / 10;
                        steps.push_back(std::max(1, (int) (options.batchSeconds / std::max(perStep, 1e-9))));
                    }
                    for (int r = 0; r < options.repeats; r++)
                        for (size_t i = 0; i < runs.size(); i++)
                            runs[i].secondsPerStep.push_back(secondsFor(*runs[i].integrator, steps[i]) / steps[i]);
                    std::map<std::pair<string, int>, double> byThreads;  // median time per (integrator, threads)
                    const int numAtoms = numBodies * k;
                    for (size_t i = 0; i < runs.size(); i++) {
                        const Run& run = runs[i];
                        double m = median(run.secondsPerStep);
                        byThreads[{run.name, run.threads}] = m;
                        auto range = std::minmax_element(run.secondsPerStep.begin(), run.secondsPerStep.end());
                        // A diverged run (NaN) is timed but flagged: its time means nothing.
                        State state = run.context->getState(State::Positions | State::Energy, false, 1 << 0);
                        bool finite = std::isfinite(state.getKineticEnergy());
                        for (const Vec3& x : state.getPositions())
                            finite = finite && std::isfinite(x[0] + x[1] + x[2]);
                        allFinite = allFinite && finite;
                        out << platformName << ',' << run.name << ',' << k << ',' << numBodies << ',' << numAtoms << ','
                            << run.constraintsPerBody << ',' << steps[i] << ',' << options.repeats << ',' << m * 1e6
                            << ',' << *range.first * 1e6 << ',' << *range.second * 1e6 << ','
                            << m * 1e9 / numAtoms << ',' << (finite ? "yes" : "no") << ',' << run.threads << '\n';
                    }
                    out.flush();
                    // met: 1 yes, 0 no, -1 no target for this configuration.
                    auto report = [&](const string& name, double value, const string& target, int met) {
                        if (!std::isfinite(value) || value == 0)
                            return;  // an integrator of the ratio was not run
                        ratios << platformName << ',' << k << ',' << numBodies << ',' << name << ',' << value << ','
                               << target << ',' << (met < 0 ? "-" : met ? "yes" : "no") << '\n';
                    };
                    // Median at the first thread count; 0 for an integrator that was not run.
                    auto medianOf = [&](const string& name) { return byThreads[{name, threadCounts[0]}]; };
                    double mr = medianOf("mrattle");
                    report("mrattle/verlet", mr / medianOf("verlet"), "<=1.5", mr / medianOf("verlet") <= 1.5);
                    report("mrattle/splitting", mr / medianOf("splitting"), "<=1.0", mr / medianOf("splitting") <= 1.0);
                    if (k == 5) {
                        double ccma = medianOf("verlet_ccma") / mr, pairs = medianOf("mrattle_allpairs") / mr;
                        report("verlet_ccma/mrattle", ccma, ">=2", ccma >= 2);
                        report("mrattle_allpairs/mrattle", pairs, "<=1.10", pairs <= 1.10);
                    }
                    if (k == 3) {
                        double settle = mr / medianOf("verlet_settle");
                        report("mrattle/verlet_settle", settle, "<=1.0", settle <= 1.0);
                    }
                    // Speed-up from threads: time at the first count over time at each other one.
                    for (size_t t = 1; t < threadCounts.size(); t++)
                        for (const string& name : {"mrattle", "splitting"}) {
                            double speedup = medianOf(name) / byThreads[{name, threadCounts[t]}];
                            string label = name + " threads " + std::to_string(threadCounts[0]) + "/" +
                                           std::to_string(threadCounts[t]);
                            if (numBodies >= 3000 && name == "mrattle")
                                report(label, speedup, ">=1.7", speedup >= 1.7);
                            else
                                report(label, speedup, "-", -1);
                        }
                    ratios.flush();
                }
            }
        }
        if (!allFinite) {
            std::cerr << "step_cost: some run diverged (finite = no in the CSV)" << std::endl;
            return 2;
        }
    } catch (const std::exception& e) {
        std::cerr << "step_cost: " << e.what() << std::endl;
        return 1;
    }
    return 0;
}
