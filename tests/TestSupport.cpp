#include "TestSupport.h"
#include "MRattleBuildInfo.h"
#include "MRattlePlatforms.h"
#include "MRattleBussiIntegrator.h"
#include "MRattleDrudeLangevinIntegrator.h"
#include "MRattleDrudeNoseHooverIntegrator.h"
#include "MRattleLangevinIntegrator.h"
#include "MRattleNoseHooverIntegrator.h"
#include "RigidSplittingIntegrator.h"
#include <gtest/gtest.h>
#include "openmm/OpenMMException.h"
#include "openmm/serialization/XmlSerializer.h"
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <random>

extern "C" void registerMRattleReferenceKernelFactories();

using namespace OpenMM;
using std::vector;

namespace MRattleTest {

void loadPlugins() {
    static std::once_flag once;
    std::call_once(once, [] {
        // The platform plugins of the OpenMM this was built against, unless the user names others.
        setenv("OPENMM_PLUGIN_DIR", MRATTLE_OPENMM_PLUGIN_DIR, 0);
        Platform::loadPluginsFromDirectory(Platform::getDefaultPluginsDirectory());
        registerMRattleReferenceKernelFactories();
        // The device platforms' kernel plugins of this build, where OpenMM has the platform;
        // from MRATTLE_PLUGIN_DIR instead of the build tree where that is set (the programs
        // copied to another machine: scripts/gpu-check.sh).
        const char* pluginDir = std::getenv("MRATTLE_PLUGIN_DIR");
        for (const MRattlePlugin::BuiltPlatform& built : MRattlePlugin::BuiltPlatforms) {
            if (!built.device)
                continue;
            std::string path = built.pluginPath;
            if (pluginDir != nullptr)
                path = std::string(pluginDir) + "/" + path.substr(path.find_last_of('/') + 1);
            for (int i = 0; i < Platform::getNumPlatforms(); i++)
                if (Platform::getPlatform(i).getName() == built.name)
                    Platform::loadPluginLibrary(path);
        }
    });
}

Platform& platform(const std::string& name) {
    loadPlugins();
    return Platform::getPlatformByName(name);
}

namespace {

bool havePlatform(const std::string& name) {
    loadPlugins();
    for (int i = 0; i < Platform::getNumPlatforms(); i++)
        if (Platform::getPlatform(i).getName() == name)
            return true;
    return false;
}

} // namespace

bool isDevicePlatform(const std::string& name) {
    for (const MRattlePlugin::BuiltPlatform& built : MRattlePlugin::BuiltPlatforms)
        if (built.device && name == built.name)
            return true;
    return false;
}

std::vector<std::string> devicePlatforms() {
    std::vector<std::string> names;
    for (const MRattlePlugin::BuiltPlatform& built : MRattlePlugin::BuiltPlatforms)
        if (built.device && havePlatform(built.name))
            names.push_back(built.name);
    return names;
}

std::string unavailable(const std::string& name) {
    if (!isDevicePlatform(name))  // a host platform: only whether OpenMM has it (an OpenMM built without CPU)
        return havePlatform(name) ? "" : "OpenMM has no " + name + " platform here";
    static std::mutex mutex;
    static std::map<std::string, std::string> reasons;
    std::lock_guard<std::mutex> lock(mutex);
    if (reasons.count(name) == 0) {
        std::string& reason = reasons[name];
        if (!havePlatform(name)) {
            // The platform's plugin did not load: say why (e.g. no libcuda.so.1 without a driver).
            reason = "OpenMM has no " + name + " platform here";
            for (const std::string& failure : Platform::getPluginLoadFailures())
                if (failure.find("libOpenMM" + name) != std::string::npos)
                    reason += " (" + failure + ")";
        }
        else {
            // The platform loads without a device (CUDA with no GPU): a Context of one particle tells.
            try {
                System system;
                system.addParticle(1.0);
                VerletIntegrator integrator(0.001);
                Context context(system, integrator, Platform::getPlatformByName(name));
            }
            catch (const std::exception& e) {
                reason = "no " + name + " device: " + e.what();
            }
        }
    }
    return reasons[name];
}

namespace {

/** An integrator class that counts the checkpoints written of its Context. */
template <class Integrator>
class CountingCheckpoints : public Integrator, public CheckpointCounter {
public:
    using Integrator::Integrator;

protected:
    void createCheckpoint(std::ostream& stream) const override {
        checkpointsWritten++;
        Integrator::createCheckpoint(stream);
    }
};

/** new Class(arguments...). */
template <class Class>
struct Construct {
    template <class... Arguments>
    Class* operator()(Arguments... arguments) const {
        return new Class(arguments...);
    }
};

/**
 * An entry's IntegratorMaker from build(construct, stepSize), which makes the integrator by
 * construct(its constructor's arguments) and sets the rest: given Construct<Class> and
 * Construct<CountingCheckpoints<Class>>, the one build makes both with the same settings.
 */
template <class Class, class Build>
IntegratorMaker maker(Build build) {
    using MRattlePlugin::RigidBodyIntegrator;
    return {[build](double h) -> RigidBodyIntegrator* { return build(Construct<Class>(), h); },
            [build](double h) -> RigidBodyIntegrator* { return build(Construct<CountingCheckpoints<Class> >(), h); }};
}

} // namespace

const std::vector<IntegratorTraits>& integrators() {
    using namespace MRattlePlugin;
    static const std::vector<IntegratorTraits> list = {
        // name, conservesEnergy, stochastic, runsOnDevicePlatforms, hasOwnState, rescalesVelocities, make, removeNoise,
        // heatBathEnergy, forcesAtStepStart
        {"MRattle", true, false, true, false, false, maker<MRattleIntegrator>([](auto make, double h) { return make(h); })},
        {"MRattleLangevin", false, true, true, true, false,
         maker<MRattleLangevinIntegrator>([](auto make, double h) {
             auto* langevin = make(300.0, 1.0, h);
             langevin->setRandomNumberSeed(2024);
             return langevin;
         }),
         [](RigidBodyIntegrator& integrator) { dynamic_cast<MRattleLangevinIntegrator&>(integrator).setTemperature(0); },
         nullptr, true},
        {"RigidSplitting", true, false, false, false, false,
         maker<RigidSplittingIntegrator>([](auto make, double h) { return make(h); })},
        {"MRattleNoseHoover", false, false, true, true, true,  // 300 K, 10/ps, chain of 3, MTS 3, Yoshida-Suzuki 7
         maker<MRattleNoseHooverIntegrator>([](auto make, double h) { return make(300.0, 10.0, h); }), nullptr,
         [](RigidBodyIntegrator& integrator) {
             return dynamic_cast<MRattleNoseHooverIntegrator&>(integrator).computeHeatBathEnergy();
         }},
        {"MRattleBussi", false, true, true, true, true,
         maker<MRattleBussiIntegrator>([](auto make, double h) {
             auto* bussi = make(300.0, 10.0, h);
             bussi->setRandomNumberSeed(2024);
             return bussi;
         }),
         [](RigidBodyIntegrator& integrator) {
             dynamic_cast<MRattleBussiIntegrator&>(integrator).setCollisionFrequency(0);
         },
         [](RigidBodyIntegrator& integrator) {
             return dynamic_cast<MRattleBussiIntegrator&>(integrator).computeHeatBathEnergy();
         }},
        // The generic suites' Systems have no DrudeForce, where it is MRattleLangevin with its own draws.
        {"MRattleDrudeLangevin", false, true, true, true, false,
         maker<MRattleDrudeLangevinIntegrator>([](auto make, double h) {
             auto* drude = make(300.0, 1.0, 1.0, 20.0, h);
             drude->setRandomNumberSeed(2024);
             return drude;
         }),
         [](RigidBodyIntegrator& integrator) {
             auto& drude = dynamic_cast<MRattleDrudeLangevinIntegrator&>(integrator);
             drude.setTemperature(0);
             drude.setDrudeTemperature(0);
         },
         nullptr, true},
        // Without a DrudeForce its Drude chain rests and it is MRattleNoseHoover with the body
        // chain on all degrees of freedom.
        {"MRattleDrudeNoseHoover", false, false, true, true, true,   // 300 K, 10/ps; Drude 1 K, 20/ps
         maker<MRattleDrudeNoseHooverIntegrator>([](auto make, double h) { return make(300.0, 10.0, 1.0, 20.0, h); }),
         nullptr,
         [](RigidBodyIntegrator& integrator) {
             return dynamic_cast<MRattleDrudeNoseHooverIntegrator&>(integrator).computeHeatBathEnergy();
         }},
    };
    return list;
}

const IntegratorTraits& integratorTraits(const std::string& name) {
    for (const IntegratorTraits& traits : integrators())
        if (traits.name == name)
            return traits;
    throw OpenMMException("no rigid-body integrator named '" + name + "' in the tests' list (integrators())");
}

std::vector<Config> configsOf(const std::string& integrator) {
    std::vector<Config> configs;
    const bool onDevices = integratorTraits(integrator).runsOnDevicePlatforms;
    for (const MRattlePlugin::BuiltPlatform& built : MRattlePlugin::BuiltPlatforms) {
        // One that cannot run here (unavailable()) keeps its configs: their tests skip, saying why.
        if (built.device && !onDevices)
            continue;
        configs.push_back({built.name, integrator});
    }
    return configs;
}

std::vector<Config> allConfigs() {
    std::vector<Config> configs;
    for (const IntegratorTraits& traits : integrators())
        for (const Config& config : configsOf(traits.name))
            configs.push_back(config);
    return configs;
}

void PrintTo(const Config& config, std::ostream* out) {
    *out << config.platform << "/" << config.integrator;
}

std::string configName(const ::testing::TestParamInfo<Config>& info) {
    return info.param.platform + "_" + info.param.integrator;
}

std::unique_ptr<MRattlePlugin::RigidBodyIntegrator> makeIntegrator(const std::string& kind, double stepSize) {
    return std::unique_ptr<MRattlePlugin::RigidBodyIntegrator>(integratorTraits(kind).make(stepSize));
}

std::unique_ptr<MRattlePlugin::RigidBodyIntegrator> makeCountingCheckpoints(const std::string& kind, double stepSize) {
    const IntegratorMaker& make = integratorTraits(kind).make;
    if (!make.countingCheckpoints)
        throw OpenMMException("integrators()'s entry for " + kind +
                              " makes no checkpoint-counting integrator: write its make as maker<Class>(...)");
    return std::unique_ptr<MRattlePlugin::RigidBodyIntegrator>(make.countingCheckpoints(stepSize));
}

std::map<std::string, std::string> platformProperties(const std::string& name) {
    if (name == "CPU")
        return {{"Threads", "1"}};
    if (isDevicePlatform(name))
        return {{"Precision", "double"}};  // the generic suites hold every platform to Reference's tolerances
    return {};
}

std::unique_ptr<Context> RigidBodyTest::makeContext(const System& system, Integrator& integrator) const {
    return std::unique_ptr<Context>(
        new Context(system, integrator, platform(GetParam().platform), platformProperties(GetParam().platform)));
}

namespace {

void addSite(Molecule& m, const Vec3& position, double mass, double charge, double sigma, double epsilon) {
    m.sites.push_back(position);
    m.masses.push_back(mass);
    m.charges.push_back(charge);
    m.sigmas.push_back(sigma);
    m.epsilons.push_back(epsilon);
}

/** Shift the sites so that their centre of mass is the origin. */
void centerOnMass(Molecule& m) {
    Vec3 center;
    double total = 0;
    for (size_t i = 0; i < m.sites.size(); i++) {
        center += m.sites[i] * m.masses[i];
        total += m.masses[i];
    }
    for (Vec3& s : m.sites)
        s -= center / total;
}

vector<Vec3> rotationFrom(std::mt19937& generator) {
    // A normalised 4D Gaussian is a uniform unit quaternion, hence a uniform rotation.
    std::normal_distribution<double> gaussian(0.0, 1.0);
    double w = gaussian(generator), x = gaussian(generator), y = gaussian(generator), z = gaussian(generator);
    double norm = std::sqrt(w * w + x * x + y * y + z * z);
    w /= norm, x /= norm, y /= norm, z /= norm;
    return {Vec3(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
            Vec3(2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
            Vec3(2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y))};
}

} // namespace

Molecule benzene() {
    Molecule m;
    const double cc = 0.1397, ch = 0.1084;
    for (int k = 0; k < 6; k++) {
        double angle = k * M_PI / 3;
        addSite(m, Vec3(cc * std::cos(angle), cc * std::sin(angle), 0), 12.011, -0.115, 0.355, 0.29288);
    }
    for (int k = 0; k < 6; k++) {
        double angle = k * M_PI / 3;
        addSite(m, Vec3((cc + ch) * std::cos(angle), (cc + ch) * std::sin(angle), 0), 1.008, 0.115, 0.242, 0.12552);
    }
    for (int k = 0; k < 6; k++) {
        m.bonds.push_back({k, (k + 1) % 6});
        m.bonds.push_back({k, k + 6});
    }
    return m;
}

Molecule tetrahedral() {
    Molecule m;
    const double s = 1 / std::sqrt(3.0);
    addSite(m, Vec3(0, 0, 0), 12.011, 0.2, 0.34, 0.35);                      // C
    addSite(m, Vec3(s, s, s) * 0.109, 1.008, 0.05, 0.25, 0.125);              // H
    addSite(m, Vec3(s, -s, -s) * 0.109, 2.014, 0.05, 0.25, 0.125);            // D
    addSite(m, Vec3(-s, s, -s) * 0.135, 18.998, -0.15, 0.295, 0.2);           // F
    addSite(m, Vec3(-s, -s, s) * 0.177, 35.453, -0.15, 0.34, 1.2);            // Cl
    for (int k = 1; k < 5; k++)
        m.bonds.push_back({0, k});
    centerOnMass(m);
    return m;
}

Molecule water() {
    Molecule m;
    const double oh = 0.09572, halfAngle = 0.5 * 104.52 * M_PI / 180;
    addSite(m, Vec3(0, 0, 0), 15.999, -0.834, 0.315061, 0.636386);
    addSite(m, Vec3(oh * std::sin(halfAngle), oh * std::cos(halfAngle), 0), 1.008, 0.417, 0.1, 0.0);
    addSite(m, Vec3(-oh * std::sin(halfAngle), oh * std::cos(halfAngle), 0), 1.008, 0.417, 0.1, 0.0);
    m.bonds.push_back({0, 1});
    m.bonds.push_back({0, 2});
    centerOnMass(m);
    return m;
}

vector<Vec3> randomRotation(unsigned int seed) {
    std::mt19937 generator(seed);
    return rotationFrom(generator);
}

Vec3 rotate(const vector<Vec3>& rotation, const Vec3& v) {
    return Vec3(rotation[0].dot(v), rotation[1].dot(v), rotation[2].dot(v));
}

vector<vector<int> > moleculeIndices(int numMolecules, int sitesPerMolecule) {
    vector<vector<int> > molecules(numMolecules);
    for (int m = 0; m < numMolecules; m++)
        for (int i = 0; i < sitesPerMolecule; i++)
            molecules[m].push_back(m * sitesPerMolecule + i);
    return molecules;
}

Cluster buildCluster(const Molecule& molecule, int n, double spacing, unsigned int seed, const ClusterOptions& options) {
    Cluster c;
    c.system.reset(new System());
    System& system = *c.system;
    const int sites = molecule.sites.size();
    const int numMolecules = n * n * n;
    c.molecules = moleculeIndices(numMolecules, sites);
    std::mt19937 generator(seed);
    const double offset = 0.5 * (n - 1) * spacing;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            for (int k = 0; k < n; k++) {
                Vec3 center(i * spacing - offset, j * spacing - offset, k * spacing - offset);
                vector<Vec3> placed;
                bool clear = false;
                for (int attempt = 0; attempt < 1000 && !clear; attempt++) {
                    vector<Vec3> rotation = rotationFrom(generator);
                    placed.clear();
                    for (const Vec3& s : molecule.sites)
                        placed.push_back(center + rotate(rotation, s));
                    clear = true;
                    for (size_t p = 0; p < c.positions.size() && clear; p++)
                        for (const Vec3& q : placed) {
                            Vec3 d = c.positions[p] - q;
                            if (d.dot(d) < options.minSiteDistance * options.minSiteDistance) {
                                clear = false;
                                break;
                            }
                        }
                }
                if (!clear)
                    throw OpenMMException("buildCluster: no orientation without overlaps at lattice spacing " +
                                          std::to_string(spacing));
                c.positions.insert(c.positions.end(), placed.begin(), placed.end());
            }
    for (int m = 0; m < numMolecules; m++)
        for (int i = 0; i < sites; i++)
            system.addParticle(molecule.masses[i]);
    if (options.method != NonbondedForce::NoCutoff) {
        double edge = n * spacing;
        system.setDefaultPeriodicBoxVectors(Vec3(edge, 0, 0), Vec3(0, edge, 0), Vec3(0, 0, edge));
    }
    if (options.bonds && !molecule.bonds.empty()) {
        HarmonicBondForce* bonds = new HarmonicBondForce();
        for (int m = 0; m < numMolecules; m++)
            for (const auto& bond : molecule.bonds) {
                Vec3 d = molecule.sites[bond.first] - molecule.sites[bond.second];
                bonds->addBond(m * sites + bond.first, m * sites + bond.second, std::sqrt(d.dot(d)), 1e5);
            }
        system.addForce(bonds);
    }
    if (options.nonbonded) {
        NonbondedForce* nonbonded = new NonbondedForce();
        nonbonded->setNonbondedMethod(options.method);
        nonbonded->setCutoffDistance(options.cutoff);
        for (int m = 0; m < numMolecules; m++)
            for (int i = 0; i < sites; i++)
                nonbonded->addParticle(options.charges ? molecule.charges[i] : 0.0, molecule.sigmas[i], molecule.epsilons[i]);
        for (const vector<int>& members : c.molecules)
            for (int i = 0; i < sites; i++)
                for (int j = i + 1; j < sites; j++)
                    nonbonded->addException(members[i], members[j], 0.0, 1.0, 0.0);
        system.addForce(nonbonded);
    }
    return c;
}

CustomIntegrator* rattleVerletIntegrator(double stepSize, double constraintTolerance) {
    CustomIntegrator* integrator = new CustomIntegrator(stepSize);
    integrator->addPerDofVariable("x0", 0);
    integrator->addUpdateContextState();
    integrator->addComputePerDof("v", "v+0.5*dt*f/m");
    integrator->addComputePerDof("x0", "x");
    integrator->addComputePerDof("x", "x+dt*v");
    integrator->addConstrainPositions();
    integrator->addComputePerDof("v", "(x-x0)/dt");
    integrator->addComputePerDof("v", "v+0.5*dt*f/m");
    integrator->addConstrainVelocities();
    integrator->setConstraintTolerance(constraintTolerance);
    return integrator;
}

vector<double> masses(const System& system) {
    vector<double> result(system.getNumParticles());
    for (int i = 0; i < system.getNumParticles(); i++)
        result[i] = system.getParticleMass(i);
    return result;
}

Vec3 totalMomentum(const vector<double>& masses, const vector<Vec3>& velocities) {
    Vec3 p;
    for (size_t i = 0; i < velocities.size(); i++)
        p += velocities[i] * masses[i];
    return p;
}

Vec3 angularMomentum(const vector<double>& masses, const vector<Vec3>& positions, const vector<Vec3>& velocities) {
    Vec3 l;
    for (size_t i = 0; i < velocities.size(); i++)
        l += positions[i].cross(velocities[i]) * masses[i];
    return l;
}

std::string messageOf(const std::function<void()>& action) {
    try {
        action();
    } catch (const OpenMMException& e) {
        return e.what();
    }
    ADD_FAILURE() << "no OpenMMException was thrown";
    return "";
}

double maxDistanceChange(const vector<Vec3>& a, const vector<Vec3>& b, const vector<vector<int> >& bodies) {
    double worst = 0;
    for (const auto& body : bodies)
        for (size_t i = 0; i < body.size(); i++)
            for (size_t j = i + 1; j < body.size(); j++) {
                Vec3 da = a[body[i]] - a[body[j]], db = b[body[i]] - b[body[j]];
                {
                    double change = std::fabs(std::sqrt(da.dot(da)) - std::sqrt(db.dot(db)));
                    if (!(change <= worst))  // NaN propagates
                        worst = change;
                }
            }
    return worst;
}

double maxDeviation(const vector<Vec3>& a, const vector<Vec3>& b) {
    double worst = 0;
    for (size_t i = 0; i < a.size(); i++) {
        Vec3 d = a[i] - b[i];
        double distance = std::sqrt(d.dot(d));
        if (!(distance <= worst))  // NaN propagates
            worst = distance;
    }
    return worst;
}

double mean(const vector<double>& values) {
    double sum = 0;
    for (double v : values)
        sum += v;
    return sum / values.size();
}

double standardDeviation(const vector<double>& values) {
    double average = mean(values), sum = 0;
    for (double v : values)
        sum += (v - average) * (v - average);
    return std::sqrt(sum / values.size());
}

double linearSlope(const vector<double>& values) {
    const double n = values.size(), meanIndex = 0.5 * (n - 1), average = mean(values);
    double covariance = 0, variance = 0;
    for (size_t i = 0; i < values.size(); i++) {
        covariance += (i - meanIndex) * (values[i] - average);
        variance += (i - meanIndex) * (i - meanIndex);
    }
    return covariance / variance;
}

std::pair<double, double> blockMean(const vector<double>& series, int blocks) {
    const size_t length = series.size() / blocks;
    vector<double> means(blocks, 0.0);
    for (int b = 0; b < blocks; b++)
        means[b] = mean(vector<double>(series.begin() + b * length, series.begin() + (b + 1) * length));
    return {mean(means), standardDeviation(means) / std::sqrt(blocks - 1.0)};  // the means' sample variance / blocks
}

Drift driftOfBlockMeans(const vector<double>& values, int blocks) {
    const size_t size = values.size() / blocks;
    vector<double> means(blocks);
    for (int b = 0; b < blocks; b++)
        means[b] = mean(vector<double>(values.begin() + b * size, values.begin() + (b + 1) * size));
    const double slope = linearSlope(means), average = mean(means), middle = 0.5 * (blocks - 1);
    double residuals = 0, spread = 0;
    for (int b = 0; b < blocks; b++) {
        const double r = means[b] - average - slope * (b - middle);
        residuals += r * r;
        spread += (b - middle) * (b - middle);
    }
    // Per block, then over the series' length (blocks * size samples).
    const double slopeError = std::sqrt(residuals / (blocks - 2) / spread);
    return {slope * blocks, slopeError * blocks};
}

std::string toXml(const Integrator& integrator) {
    std::stringstream stream;
    XmlSerializer::serialize<Integrator>(&integrator, "Integrator", stream);
    return stream.str();
}

std::unique_ptr<Integrator> fromXml(const std::string& xml) {
    std::stringstream stream(xml);
    return std::unique_ptr<Integrator>(XmlSerializer::deserialize<Integrator>(stream));
}

std::string messageOfXmlWith(const std::string& xml, const std::string& original, const std::string& replacement) {
    std::string text = xml;
    const size_t at = text.find(original);
    EXPECT_NE(std::string::npos, at) << "the XML has no " << original;
    if (at == std::string::npos)
        return "";
    text.replace(at, original.size(), replacement);
    return messageOf([&] { fromXml(text); });
}

} // namespace MRattleTest
