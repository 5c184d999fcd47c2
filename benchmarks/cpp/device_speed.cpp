// device_speed: M-RATTLE against OpenMM's SETTLE on a device platform (CUDA, OpenCL), rigid TIP3P
// boxes, ns/day with PME and the integration's own cost; options and output in docs/benchmarks-cpp.md.
// C++ so that it runs where there is no Python OpenMM. Exit 2: a run diverged or lost its geometry;
// 3: the platform or the plugin's kernels on it are not there.
#include "MRattleBuildInfo.h"
#include "MRattleBussiIntegrator.h"
#include "MRattleIntegrator.h"
#include "MRattleLangevinIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "MRattlePlatforms.h"
#include "OpenMM.h"
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

using namespace OpenMM;
using std::string;
using std::vector;

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

double median(vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 == 1 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

/** The items of a comma-separated option value. */
vector<string> split(const string& text) {
    vector<string> parts;
    std::stringstream stream(text);
    for (string part; std::getline(stream, part, ',');)
        if (!part.empty())
            parts.push_back(part);
    return parts;
}

struct Options {
    string platform = "CUDA", precision = "mixed", out, ratios;
    vector<int> watersPerSide = {20, 32, 69};  // 24,000, 98,304 and 985,527 atoms
    vector<string> plugins, systems = {"bare", "pme"}, integrators;  // integrators: all of Compared if empty
    int repeats = 3, warmup = 20;
    double batchSeconds = 0.5;
};

Options parse(int argc, char** argv) {
    Options options;
    for (const MRattlePlugin::BuiltPlatform& built : MRattlePlugin::BuiltPlatforms)
        if (built.device)
            options.plugins.push_back(built.pluginPath);
    for (int i = 1; i < argc; i++) {
        const string flag = argv[i];
        if (i + 1 >= argc)
            throw std::runtime_error("device_speed: " + flag + " needs a value");
        const string value = argv[++i];
        std::map<string, string*> texts = {{"--platform", &options.platform}, {"--precision", &options.precision},
                                           {"--out", &options.out}, {"--ratios", &options.ratios}};
        std::map<string, vector<string>*> lists = {
            {"--plugins", &options.plugins}, {"--systems", &options.systems}, {"--integrators", &options.integrators}};
        if (texts.count(flag))
            *texts[flag] = value;
        else if (lists.count(flag))
            *lists[flag] = split(value);
        else if (flag == "--waters-per-side") {
            options.watersPerSide.clear();
            for (const string& part : split(value))
                options.watersPerSide.push_back(std::stoi(part));
        }
        else if (flag == "--repeats")
            options.repeats = std::stoi(value);
        else if (flag == "--batch-seconds")
            options.batchSeconds = std::stod(value);
        else
            throw std::runtime_error("device_speed: unknown option " + flag);
    }
    if (options.repeats < 1 || options.batchSeconds <= 0)
        throw std::runtime_error("device_speed: --repeats must be >= 1 and --batch-seconds > 0");
    for (int n : options.watersPerSide)
        if (n < 6)
            throw std::runtime_error("device_speed: --waters-per-side must be >= 6 (the box must hold the 0.9 nm cutoff)");
    return options;
}

// TIP3P (Jorgensen 1983): geometry, masses, charges, oxygen Lennard-Jones.
const double OH = 0.09572, HOH = 104.52 * M_PI / 180, HH = 2 * OH * std::sin(HOH / 2);
const double MassO = 15.9994, MassH = 1.008, ChargeO = -0.834, ChargeH = 0.417;
const double SigmaO = 0.315061, EpsilonO = 0.636386;
const double WatersPerNm3 = 33.43, Cutoff = 0.9, StepSize = 0.002;

struct WaterBox {
    int waters = 0;
    double side = 0;  // nm
    vector<Vec3> positions;
};

/** A uniformly random rotation (rows) from a unit quaternion. */
vector<Vec3> randomRotation(std::mt19937& generator) {
    std::normal_distribution<double> normal;
    double q[4], norm = 0;
    for (double& c : q) {
        c = normal(generator);
        norm += c * c;
    }
    norm = std::sqrt(norm);
    const double w = q[0] / norm, x = q[1] / norm, y = q[2] / norm, z = q[3] / norm;
    return {Vec3(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
            Vec3(2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
            Vec3(2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y))};
}

/**
 * n^3 waters on a cubic lattice at liquid density, each in a random orientation; an
 * orientation that brings a site within 0.17 nm of a site of an already placed neighbour
 * (periodic) is redrawn, up to 50 times.
 */
WaterBox buildWaterBox(int n, unsigned int seed) {
    WaterBox box;
    box.waters = n * n * n;
    box.side = std::cbrt(box.waters / WatersPerNm3);
    const double spacing = box.side / n;
    // The sites about the oxygen: H1 and H2 in the xy plane.
    const vector<Vec3> local = {Vec3(0, 0, 0), Vec3(OH * std::sin(HOH / 2), OH * std::cos(HOH / 2), 0),
                                Vec3(-OH * std::sin(HOH / 2), OH * std::cos(HOH / 2), 0)};
    std::mt19937 generator(seed);
    box.positions.resize(3 * box.waters);
    auto index = [n](int i, int j, int k) { return ((i + n) % n) + n * (((j + n) % n) + n * ((k + n) % n)); };
    vector<char> placed(box.waters, 0);
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                const int w = index(i, j, k);
                const Vec3 center((i + 0.5) * spacing, (j + 0.5) * spacing, (k + 0.5) * spacing);
                for (int attempt = 0; attempt < 50; attempt++) {
                    vector<Vec3> rotation = randomRotation(generator);
                    for (int s = 0; s < 3; s++)
                        box.positions[3 * w + s] = center + Vec3(rotation[0].dot(local[s]), rotation[1].dot(local[s]),
                                                                 rotation[2].dot(local[s]));
                    double closest = 1e10;
                    for (int dk = -1; dk <= 1; dk++)
                        for (int dj = -1; dj <= 1; dj++)
                            for (int di = -1; di <= 1; di++) {
                                const int other = index(i + di, j + dj, k + dk);
                                if (other == w || !placed[other])
                                    continue;
                                for (int a = 0; a < 3; a++)
                                    for (int b = 0; b < 3; b++) {
                                        Vec3 d = box.positions[3 * w + a] - box.positions[3 * other + b];
                                        for (int c = 0; c < 3; c++)
                                            d[c] -= box.side * std::round(d[c] / box.side);
                                        closest = std::min(closest, std::sqrt(d.dot(d)));
                                    }
                            }
                    if (closest >= 0.17)
                        break;
                }
                placed[w] = 1;
            }
    return box;
}

/** The waters' particles and constraints, and either TIP3P with PME or a negligible force. */
std::unique_ptr<System> buildSystem(const WaterBox& box, bool pme) {
    std::unique_ptr<System> system(new System());
    system->setDefaultPeriodicBoxVectors(Vec3(box.side, 0, 0), Vec3(0, box.side, 0), Vec3(0, 0, box.side));
    NonbondedForce* nonbonded = pme ? new NonbondedForce() : nullptr;
    for (int w = 0; w < box.waters; w++) {
        const int o = system->addParticle(MassO);
        system->addParticle(MassH);
        system->addParticle(MassH);
        system->addConstraint(o, o + 1, OH);
        system->addConstraint(o, o + 2, OH);
        system->addConstraint(o + 1, o + 2, HH);
        if (pme) {
            nonbonded->addParticle(ChargeO, SigmaO, EpsilonO);
            nonbonded->addParticle(ChargeH, 1, 0);
            nonbonded->addParticle(ChargeH, 1, 0);
            nonbonded->addException(o, o + 1, 0, 1, 0);
            nonbonded->addException(o, o + 2, 0, 1, 0);
            nonbonded->addException(o + 1, o + 2, 0, 1, 0);
        }
    }
    if (pme) {
        nonbonded->setNonbondedMethod(NonbondedForce::PME);
        nonbonded->setCutoffDistance(Cutoff);
        system->addForce(nonbonded);
    }
    else {
        CustomExternalForce* negligible = new CustomExternalForce("0*x");
        negligible->addParticle(0);
        system->addForce(negligible);
    }
    return system;
}

/**
 * Each timed integrator, the one its time is compared with and the target of that ratio (bare
 * systems: integration time at most this; PME: ns/day at least 0.95x). "mrattle_large_bodies"
 * groups the waters into ten bodies of up to LargeBodyWaters waters: against the same atoms
 * as 3-atom bodies, the cost of large bodies per atom.
 */
struct Compared {
    string name, against;
    double target;
};
const vector<Compared> Comparisons = {
    {"verlet_settle", "", 0},          {"mrattle", "verlet_settle", 1.2},
    {"langevin_settle", "", 0},        {"mrattle_langevin", "langevin_settle", 1.2},
    {"nosehoover_settle", "", 0},      {"mrattle_nosehoover", "nosehoover_settle", 1.3},
    {"mrattle_bussi", "nosehoover_settle", 1.3}, {"mrattle_large_bodies", "mrattle", 1.5}};
const int LargeBodyWaters = 333;

std::unique_ptr<Integrator> makeIntegrator(const string& name, int waters) {
    if (name == "verlet_settle")
        return std::unique_ptr<Integrator>(new VerletIntegrator(StepSize));
    if (name == "langevin_settle")
        return std::unique_ptr<Integrator>(new LangevinMiddleIntegrator(300, 1, StepSize));
    if (name == "nosehoover_settle")
        return std::unique_ptr<Integrator>(new NoseHooverIntegrator(300, 10, StepSize));
    MRattlePlugin::RigidBodyIntegrator* rigid;
    if (name == "mrattle_langevin")
        rigid = new MRattlePlugin::MRattleLangevinIntegrator(300, 1, StepSize);
    else if (name == "mrattle_nosehoover")
        rigid = new MRattlePlugin::MRattleNoseHooverIntegrator(300, 10, StepSize);
    else if (name == "mrattle_bussi")
        rigid = new MRattlePlugin::MRattleBussiIntegrator(300, 10, StepSize);
    else if (name == "mrattle" || name == "mrattle_large_bodies")
        rigid = new MRattlePlugin::MRattleIntegrator(StepSize);
    else
        throw std::runtime_error("device_speed: unknown integrator " + name);
    const int perBody = std::min(LargeBodyWaters, waters / 10), grouped = name == "mrattle_large_bodies" ? 10 * perBody : 0;
    for (int first = 0; first < grouped; first += perBody) {
        vector<int> body;
        for (int w = first; w < first + perBody; w++)
            body.insert(body.end(), {3 * w, 3 * w + 1, 3 * w + 2});
        rigid->addRigidBody(body);
    }
    for (int w = grouped; w < waters; w++)
        rigid->addRigidBody({3 * w, 3 * w + 1, 3 * w + 2});
    return std::unique_ptr<Integrator>(rigid);
}

/** One timed configuration: its own System, Integrator and Context. */
struct Run {
    string name;
    std::unique_ptr<Integrator> integrator;
    std::unique_ptr<Context> context;
    int steps = 0;
    vector<double> secondsPerStep;
};

/** Time to download the positions alone (the synchronisation ending each batch). */
double syncSeconds(Context& context) {
    context.getState(State::Positions);
    double fastest = INFINITY;
    for (int i = 0; i < 3; i++) {
        Clock::time_point start = Clock::now();
        context.getState(State::Positions);
        fastest = std::min(fastest, secondsSince(start));
    }
    return fastest;
}

/** Seconds per step over a batch of steps, ended by a download of the positions. */
double timeBatch(Run& run, int steps, double sync) {
    Clock::time_point start = Clock::now();
    run.integrator->step(steps);
    run.context->getState(State::Positions);
    return std::max(0.0, secondsSince(start) - sync) / steps;
}

/** Largest error (nm) of any O-H or H-H distance, or infinity if a position is not finite. */
double geometryError(const vector<Vec3>& x) {
    double worst = 0;
    for (size_t o = 0; o + 2 < x.size(); o += 3)
        for (const double error : {std::fabs(std::sqrt((x[o + 1] - x[o]).dot(x[o + 1] - x[o])) - OH),
                                   std::fabs(std::sqrt((x[o + 2] - x[o]).dot(x[o + 2] - x[o])) - OH),
                                   std::fabs(std::sqrt((x[o + 2] - x[o + 1]).dot(x[o + 2] - x[o + 1])) - HH)}) {
            if (!std::isfinite(error))
                return INFINITY;
            worst = std::max(worst, error);
        }
    return worst;
}

/** The geometric mean of the ratios of batches timed one after the other, and its 95% interval. */
struct PairedRatio {
    double ratio, low, high;
};

/**
 * a's batch times over b's, batch by batch (adjacent in time, so they share the machine's
 * state): exp(mean log ratio) and exp(mean +- 2 standard errors); inverted for ns/day.
 * The interval is what a ratio of one run can claim on a noisy machine.
 */
PairedRatio pairedRatio(const vector<double>& a, const vector<double>& b, bool invert) {
    const size_t n = std::min(a.size(), b.size());
    double sum = 0, sumSquares = 0;
    for (size_t r = 0; r < n; r++) {
        const double x = std::log(a[r] / b[r]) * (invert ? -1 : 1);
        sum += x;
        sumSquares += x * x;
    }
    const double mean = sum / n;
    const double error = n > 1 ? std::sqrt(std::max(0.0, sumSquares / n - mean * mean) / (n - 1)) : INFINITY;
    return {std::exp(mean), std::exp(mean - 2 * error), std::exp(mean + 2 * error)};
}

/** One line of --ratios: a's times over b's (inverted: b's over a's, as ns/day), against its target, and the paired ratio. */
void writeRatio(std::ostream& ratios, const string& system, int atoms, const string& measure, const vector<double>& a,
                const vector<double>& b, bool invert, double target) {
    const double value = invert ? median(b) / median(a) : median(a) / median(b);
    const PairedRatio paired = pairedRatio(a, b, invert);
    ratios << system << "," << atoms << "," << measure << "," << std::setprecision(3) << value << ","
           << (invert ? ">= " : "<= ") << target << "," << ((invert ? value >= target : value <= target) ? "yes" : "no")
           << "," << paired.ratio << "," << paired.low << "," << paired.high << std::endl;
}

} // namespace

int main(int argc, char** argv) {
    try {
        Options options = parse(argc, argv);
        const Clock::time_point begin = Clock::now();
        // OpenMM's platforms: OPENMM_PLUGIN_DIR, else those of the OpenMM this was built against.
        setenv("OPENMM_PLUGIN_DIR", MRATTLE_OPENMM_PLUGIN_DIR, 0);
        Platform::loadPluginsFromDirectory(Platform::getDefaultPluginsDirectory());
        for (const string& failure : Platform::getPluginLoadFailures())
            std::cerr << "device_speed: an OpenMM plugin did not load: " << failure << "\n";
        for (const string& plugin : options.plugins) {
            try {
                Platform::loadPluginLibrary(plugin);
            }
            catch (const std::exception& e) {
                std::cerr << "device_speed: the kernel plugin " << plugin << " did not load: " << e.what() << "\n";
            }
        }
        Platform* found = nullptr;
        for (int i = 0; i < Platform::getNumPlatforms(); i++)
            found = Platform::getPlatform(i).getName() == options.platform ? &Platform::getPlatform(i) : found;
        if (found == nullptr) {
            std::cerr << "device_speed: OpenMM " << Platform::getOpenMMVersion() << " has no " << options.platform
                      << " platform here (see the plugin load failures above)\n";
            return 3;
        }
        Platform& platform = *found;
        if (!platform.supportsKernels({"IntegrateMRattleStep", "IntegrateMRattleLangevinStep"})) {
            std::cerr << "device_speed: the plugin's kernels are not registered on " << options.platform
                      << " (give their library with --plugins)\n";
            return 3;
        }
        // Timings to --out (default stdout), the targets to --ratios (default stderr).
        std::ofstream outFile, ratiosFile;
        if (!options.out.empty())
            outFile.open(options.out);
        if (!options.ratios.empty())
            ratiosFile.open(options.ratios);
        std::ostream& out = options.out.empty() ? std::cout : outFile;
        std::ostream& ratios = options.ratios.empty() ? std::cerr : ratiosFile;
        if (!out || !ratios)
            throw std::runtime_error("cannot write " + options.out + " or " + options.ratios);
        out << "platform,device,precision,system,waters,atoms,integrator,steps_per_batch,batches,sync_ms,"
               "median_ms_per_step,min_ms_per_step,max_ms_per_step,ns_per_day,geometry_error_nm,finite\n";
        ratios << "system,atoms,measure,value,target,met,paired_ratio,ci95_low,ci95_high\n";
        vector<string> names;
        for (const Compared& compared : Comparisons)
            if (options.integrators.empty() ||
                std::count(options.integrators.begin(), options.integrators.end(), compared.name))
                names.push_back(compared.name);
        bool allGood = true;
        string device = "?";
        std::cerr << "device_speed: OpenMM " << Platform::getOpenMMVersion() << ", " << options.platform << ", "
                  << options.precision << " precision\n";
        for (int n : options.watersPerSide) {
            WaterBox box = buildWaterBox(n, 1234 + n);
            for (bool pme : {false, true}) {
                const string systemName = pme ? "pme" : "bare";
                if (std::find(options.systems.begin(), options.systems.end(), systemName) == options.systems.end())
                    continue;
                const int atoms = 3 * box.waters;
                std::unique_ptr<System> system = buildSystem(box, pme);
                vector<Run> runs;
                for (const string& name : names) {
                    Run run;
                    run.name = name;
                    run.integrator = makeIntegrator(name, box.waters);
                    Clock::time_point start = Clock::now();
                    run.context.reset(new Context(*system, *run.integrator, platform, {{"Precision", options.precision}}));
                    run.context->setPositions(box.positions);
                    run.context->setVelocitiesToTemperature(300, 1);
                    try {
                        device = platform.getPropertyValue(*run.context, "DeviceName");
                    }
                    catch (const OpenMMException&) {
                    }
                    std::cerr << "device_speed: " << systemName << ", " << atoms << " atoms, " << name
                              << ": Context in " << std::setprecision(3) << secondsSince(start) << " s\n";
                    runs.push_back(std::move(run));
                }
                // Warm up, then size each batch to about batchSeconds (whole hundreds of steps
                // when that many; each batch is one step(n), which checks the failure flag at its end).
                vector<double> sync;
                for (Run& run : runs) {
                    run.integrator->step(options.warmup);
                    sync.push_back(syncSeconds(*run.context));
                    double perStep = std::max(1e-7, timeBatch(run, options.warmup, sync.back()));
                    int steps = std::max(10, (int) (options.batchSeconds / perStep));
                    run.steps = steps >= 200 ? 100 * (steps / 100) : steps;
                }
                for (int r = 0; r < options.repeats; r++)
                    for (size_t i = 0; i < runs.size(); i++)
                        runs[i].secondsPerStep.push_back(timeBatch(runs[i], runs[i].steps, sync[i]));
                for (size_t i = 0; i < runs.size(); i++) {
                    Run& run = runs[i];
                    const double m = median(run.secondsPerStep);
                    auto range = std::minmax_element(run.secondsPerStep.begin(), run.secondsPerStep.end());
                    State state = run.context->getState(State::Positions | State::Energy);
                    const double error = geometryError(state.getPositions());
                    const bool finite = std::isfinite(state.getKineticEnergy() + state.getPotentialEnergy()) &&
                                        std::isfinite(error);
                    // SETTLE holds the geometry to OpenMM's tolerance; M-RATTLE to round-off.
                    if (!finite || error > 1e-4)
                        allGood = false;
                    out << options.platform << ",\"" << device << "\"," << options.precision << "," << systemName
                        << "," << box.waters << "," << atoms << "," << run.name << "," << run.steps << ","
                        << options.repeats << "," << std::setprecision(4) << 1e3 * sync[i] << "," << 1e3 * m << ","
                        << 1e3 * *range.first << "," << 1e3 * *range.second << ","
                        << (m > 0 ? StepSize * 1e-3 * 86400 / m : INFINITY) << "," << std::setprecision(3) << error
                        << "," << (finite ? "yes" : "no") << std::endl;
                }
                // Bare systems: setState of each Context's own State (positions and velocities),
                // SetStateCalls calls and one read per batch, interleaved; every M-RATTLE
                // integrator's against Verlet + SETTLE's.
                const int SetStateCalls = 10;
                const auto verlet = std::find(names.begin(), names.end(), "verlet_settle");
                vector<vector<double> > setState(runs.size());
                for (int r = 0; r < (pme || verlet == names.end() ? 0 : options.repeats); r++)
                    for (size_t i = 0; i < runs.size(); i++) {
                        const State state = runs[i].context->getState(State::Positions | State::Velocities);
                        Clock::time_point start = Clock::now();
                        for (int call = 0; call < SetStateCalls; call++)
                            runs[i].context->setState(state);
                        runs[i].context->getState(State::Positions);
                        setState[i].push_back(std::max(1e-9, secondsSince(start) - sync[i]) / SetStateCalls);
                    }
                for (size_t i = 0; i < runs.size(); i++)
                    if (!setState[i].empty() && runs[i].name.rfind("mrattle", 0) == 0)
                        writeRatio(ratios, systemName, atoms, runs[i].name + " setState over verlet_settle (" +
                                   std::to_string(1e3 * median(setState[i])) + " ms)", setState[i],
                                   setState[verlet - names.begin()], false, 2);
                // The targets: integration (bare) at most the pair's target times the other's
                // time; ns/day with PME at least 0.95x the other's (time ratio at most 1/0.95).
                for (const Compared& compared : Comparisons) {
                    const auto mine = std::find(names.begin(), names.end(), compared.name);
                    const auto other = std::find(names.begin(), names.end(), compared.against);
                    if (mine != names.end() && other != names.end())
                        writeRatio(ratios, systemName, atoms, compared.name + (pme ? " ns/day over " : " time per step over ") +
                                   compared.against, runs[mine - names.begin()].secondsPerStep,
                                   runs[other - names.begin()].secondsPerStep, pme, pme ? 0.95 : compared.target);
                }
            }
        }
        std::cerr << "device_speed: done in " << std::setprecision(4) << secondsSince(begin) << " s on " << device << "\n";
        return allGood ? 0 : 2;
    }
    catch (const std::exception& e) {
        std::cerr << "device_speed: " << e.what() << "\n";
        return 1;
    }
}
