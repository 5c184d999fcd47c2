#ifndef MRATTLE_TEST_SUPPORT_H_
#define MRATTLE_TEST_SUPPORT_H_

#include "MRattleIntegrator.h"
#include "OpenMM.h"
#include <gtest/gtest.h>
#include <map>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace MRattleTest {

/** Load OpenMM's plugins (for the CPU platform) and register this plugin's kernels. Idempotent. */
void loadPlugins();
OpenMM::Platform& platform(const std::string& name);

/** Counts the checkpoints written of an integrator's Context (its createCheckpoint() calls). */
struct CheckpointCounter {
    virtual ~CheckpointCounter() = default;
    mutable int checkpointsWritten = 0;
};

/**
 * How an entry of integrators() makes its integrator, written once (maker<Class>(build) in
 * TestSupport.cpp): of its class, or of a subclass of it that is also a CheckpointCounter,
 * with the same settings.
 */
struct IntegratorMaker {
    std::function<MRattlePlugin::RigidBodyIntegrator*(double stepSize)> plain;
    std::function<MRattlePlugin::RigidBodyIntegrator*(double stepSize)> countingCheckpoints;
    MRattlePlugin::RigidBodyIntegrator* operator()(double stepSize) const {
        return plain(stepSize);
    }
};

/**
 * A rigid-body integrator as the generic suites see it: what it is called, what it
 * promises, where it runs and how to make one. integrators() lists them: a new integrator
 * gets every generic suite by one entry there, and its tests ask for properties, never for
 * names.
 */
struct IntegratorTraits {
    /** "MRattle": the class name without "Integrator", for test names and messages. */
    std::string name;
    /** Deterministic and energy-conserving (velocity Verlet): NVE energy, velocities at the positions' time. */
    bool conservesEnergy;
    /** Draws random numbers: a run continues bit for bit only with its random state (on a device, OpenMM's). */
    bool stochastic;
    /** Runs on the device platforms (OpenCL, CUDA) as well as Reference and CPU. */
    bool runsOnDevicePlatforms;
    /**
     * Keeps state of its own beyond positions and velocities (a random stream, a thermostat's
     * variables): after Context::setState() of a State without its integrator parameters it
     * continues otherwise than from a checkpoint (with them, only a random stream differs).
     */
    bool hasOwnState;
    /** Its step first scales every velocity by a thermostat's factor: a motion a test sets up is changed before the drift. */
    bool rescalesVelocities;
    /**
     * One with this step size (a thermostat: 300 K, a fixed random seed: two Contexts draw the
     * same noise); written as maker<Class>(...), which also makes the checkpoint-counting one.
     */
    IntegratorMaker make;
    /**
     * A stochastic one's noise turned off (device and host draw different numbers: what is left
     * must agree): Langevin at 0 K, its friction kept; CSVR uncoupled; else none.
     */
    std::function<void(MRattlePlugin::RigidBodyIntegrator&)> removeNoise;
    /**
     * A thermostat with variables a State carries in its integrator parameters: the energy of
     * its heat bath (computeHeatBathEnergy()); else none.
     */
    std::function<double(MRattlePlugin::RigidBodyIntegrator&)> heatBathEnergy;
    /** Computes its forces at each step's start (leapfrog, as LangevinMiddleIntegrator), not after its drift. */
    bool forcesAtStepStart = false;
};
/** Every rigid-body integrator of the plugin. */
const std::vector<IntegratorTraits>& integrators();
/** The entry of integrators() with this name; throws if there is none. */
const IntegratorTraits& integratorTraits(const std::string& name);

/**
 * One platform and one rigid-body integrator: the generic suites (TEST_P) run for every
 * combination in allConfigs(), so a new platform or integrator gets the whole suite by
 * adding it there (BuiltPlatforms, integrators()).
 */
struct Config {
    std::string platform;    // a name from the build's list of platforms (MRattlePlatforms.h)
    std::string integrator;  // a name from integrators()
    const IntegratorTraits& traits() const {
        return integratorTraits(integrator);
    }
};
/** How GoogleTest prints a Config (in test names and failures). */
void PrintTo(const Config& config, std::ostream* out);
/** Every platform with the plugin's kernels, times every rigid-body integrator. */
std::vector<Config> allConfigs();
/** Every platform that runs this integrator (the device platforms only those that runsOnDevicePlatforms). */
std::vector<Config> configsOf(const std::string& integrator);
/** The device platforms (OpenCL, CUDA) of the build's list that OpenMM has here. */
std::vector<std::string> devicePlatforms();
/** Whether a platform of the build's list is a device platform. */
bool isDevicePlatform(const std::string& name);
/**
 * Why a platform of the build's list cannot run here ("" if it can): OpenMM has no such
 * platform (its plugin did not load, or OpenMM was built without it), or a device platform
 * has no device (CUDA without a GPU: found by making a Context of one particle, once per
 * process).
 */
std::string unavailable(const std::string& name);
/** In a test or SetUp(): skip, saying why, if the platform cannot run here. */
#define MRATTLE_SKIP_IF_UNAVAILABLE(platformName)                                   \
    do {                                                                          \
        const std::string mrattleWhy = MRattleTest::unavailable(platformName);    \
        if (!mrattleWhy.empty())                                                  \
            GTEST_SKIP() << mrattleWhy;                                           \
    } while (0)
/** "Reference_MRattle": a test-name suffix. */
std::string configName(const ::testing::TestParamInfo<Config>& info);
/** The integrator of that name in integrators(). */
std::unique_ptr<MRattlePlugin::RigidBodyIntegrator> makeIntegrator(const std::string& kind, double stepSize);
/** The same, of a subclass that counts the checkpoints written of its Context: dynamic_cast it to CheckpointCounter. */
std::unique_ptr<MRattlePlugin::RigidBodyIntegrator> makeCountingCheckpoints(const std::string& kind, double stepSize);
/** Platform properties of the tests: one thread on CPU (several sum forces in varying order), double precision on OpenCL. */
std::map<std::string, std::string> platformProperties(const std::string& platform);

/**
 * Skip a generic test that checks what only an energy-conserving integrator has (energy
 * conservation, a temperature that stays as set, a run that continues bit for bit without
 * a random stream), saying why.
 */
#define SKIP_UNLESS_CONSERVES_ENERGY(config)                                                            \
    if (!(config).traits().conservesEnergy)                                                             \
        GTEST_SKIP() << (config).integrator << " is a thermostat: this test checks a property of an "   \
                        "energy-conserving integrator (NVE energy, on-step velocities, no random stream)";

/** The fixture of the generic suites. */
class RigidBodyTest : public ::testing::TestWithParam<Config> {
protected:
    void SetUp() override {
        MRATTLE_SKIP_IF_UNAVAILABLE(GetParam().platform);
    }
    std::unique_ptr<MRattlePlugin::RigidBodyIntegrator> makeIntegrator(double stepSize) const {
        return MRattleTest::makeIntegrator(GetParam().integrator, stepSize);
    }
    /** A Context on this config's platform (one thread on CPU); the integrator must outlive it. */
    std::unique_ptr<OpenMM::Context> makeContext(const OpenMM::System& system, OpenMM::Integrator& integrator) const;
};

/** A rigid molecule: site positions (nm) about its centre, masses, LJ and charges. */
struct Molecule {
    std::vector<OpenMM::Vec3> sites;
    std::vector<double> masses, charges, sigmas, epsilons;
    /** Pairs joined by bonds (these make OpenMM see one molecule). */
    std::vector<std::pair<int, int> > bonds;
};

/** Benzene: 12 sites, C-C 0.1397 nm, C-H 0.1084 nm, OPLS-AA-like C and H. Planar. */
Molecule benzene();

/**
 * A non-planar 5-site molecule like CHDFCl: a centre bonded to 4 sites in tetrahedral
 * directions at different distances, all five masses distinct (three distinct principal
 * moments). Neutral. Sites are about the centre of mass.
 */
Molecule tetrahedral();

/** Rigid 3-site water, TIP3P geometry (O-H 0.09572 nm, H-O-H 104.52 degrees) and parameters. */
Molecule water();

/** Options of buildCluster(). */
struct ClusterOptions {
    /** Add a HarmonicBondForce on the molecule's bonds (at their initial lengths), so OpenMM sees molecules. */
    bool bonds = true;
    /** Add a NonbondedForce (LJ + charges) between molecules, all pairs inside a molecule excluded. */
    bool nonbonded = true;
    /** Charges in the NonbondedForce (else zero). */
    bool charges = true;
    /** NoCutoff (vacuum) or a periodic method (the box is then n * spacing on each side). */
    OpenMM::NonbondedForce::NonbondedMethod method = OpenMM::NonbondedForce::NoCutoff;
    double cutoff = 1.0;
    /** Smallest distance (nm) allowed between sites of different molecules; orientations are redrawn until met. */
    double minSiteDistance = 0.22;
};

/** A System of identical molecules with their positions and the particles of each molecule. */
struct Cluster {
    std::unique_ptr<OpenMM::System> system;
    std::vector<OpenMM::Vec3> positions;
    std::vector<std::vector<int> > molecules;
};

/**
 * n x n x n copies of a molecule on a cubic lattice of the given spacing (nm), centred on
 * the origin, each in a random orientation drawn from the seed. An orientation that brings
 * two sites of different molecules closer than options.minSiteDistance is redrawn.
 *
 * Nonbonded interactions use OpenMM's NonbondedForce with per-particle sigma and epsilon:
 * its combination is Lorentz-Berthelot (arithmetic sigma, geometric epsilon). The tests only
 * need some smooth intermolecular force, so the exact combination rule does not matter.
 */
Cluster buildCluster(const Molecule& molecule, int n, double spacing, unsigned int seed,
                     const ClusterOptions& options = ClusterOptions());

/** Particle indices of numMolecules consecutive molecules of sitesPerMolecule sites each. */
std::vector<std::vector<int> > moleculeIndices(int numMolecules, int sitesPerMolecule);

/** A uniformly distributed random rotation matrix (rows) from the generator's seed. */
std::vector<OpenMM::Vec3> randomRotation(unsigned int seed);
/** rotation * v for a rotation returned by randomRotation(). */
OpenMM::Vec3 rotate(const std::vector<OpenMM::Vec3>& rotation, const OpenMM::Vec3& v);

/**
 * Velocity Verlet with RATTLE as a CustomIntegrator, the independent reference for
 * M-RATTLE: half kick, drift, constrain positions (along the old bond vectors), velocity
 * from the constrained displacement, half kick with the new forces, constrain velocities.
 * Without constraints it is plain velocity Verlet. The caller owns the result.
 */
OpenMM::CustomIntegrator* rattleVerletIntegrator(double stepSize, double constraintTolerance);

/** An integrator's XML (OpenMM's XmlSerializer, as "Integrator"). */
std::string toXml(const OpenMM::Integrator& integrator);
/** The integrator that XML describes (XmlSerializer; throws what it throws). */
std::unique_ptr<OpenMM::Integrator> fromXml(const std::string& xml);
/** The message of reading an integrator's XML with the first `original` replaced by `replacement` (and a test failure if it is not there, or if reading does not throw). */
std::string messageOfXmlWith(const std::string& xml, const std::string& original, const std::string& replacement);

/** Particle masses of a System. */
std::vector<double> masses(const OpenMM::System& system);
/** Total linear momentum sum m_i v_i. */
OpenMM::Vec3 totalMomentum(const std::vector<double>& masses, const std::vector<OpenMM::Vec3>& velocities);
/** Total angular momentum sum m_i x_i x v_i about the origin (space frame). */
OpenMM::Vec3 angularMomentum(const std::vector<double>& masses, const std::vector<OpenMM::Vec3>& positions,
                             const std::vector<OpenMM::Vec3>& velocities);

/** The message of the OpenMMException that action throws ("" and a test failure if none). */
std::string messageOf(const std::function<void()>& action);

/** Largest change of any intra-body distance between two configurations. */
double maxDistanceChange(const std::vector<OpenMM::Vec3>& a, const std::vector<OpenMM::Vec3>& b,
                         const std::vector<std::vector<int> >& bodies);

/** Largest |a_i - b_i| over all particles. */
double maxDeviation(const std::vector<OpenMM::Vec3>& a, const std::vector<OpenMM::Vec3>& b);

/** Mean and population standard deviation of a series. */
double mean(const std::vector<double>& values);
double standardDeviation(const std::vector<double>& values);
/** Slope of the least-squares line through (i, values[i]), per sample. */
double linearSlope(const std::vector<double>& values);
/** Mean and standard error of a series, from the means of `blocks` equal blocks. */
std::pair<double, double> blockMean(const std::vector<double>& series, int blocks = 20);
/** A series' change over its length (the line through its block means) and that change's standard error. */
struct Drift {
    double change, error;
};
/** The least-squares line through the means of `blocks` equal blocks; its error from their scatter about it. */
Drift driftOfBlockMeans(const std::vector<double>& values, int blocks = 10);

} // namespace MRattleTest

#endif
