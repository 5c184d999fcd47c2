/*
 * Around the rigid minimizer: its reporter interface from C++ (OpenMM 8's report() on every
 * OpenMM version), and what happens when a Cartesian minimizer (OpenMM's LocalEnergyMinimizer
 * as a C++ caller gets it) deforms the bodies: its result becomes their shapes, on every platform.
 */
#include "RigidBodyMinimizer.h"
#include "MRattleIntegrator.h"
#include "TestSupport.h"
#include "openmm/LocalEnergyMinimizer.h"
#include <gtest/gtest.h>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::vector;

namespace {
class MinimizerHooks : public RigidBodyTest {};
} // namespace

TEST_P(MinimizerHooks, CartesianMinimizationFromCppGivesTheBodiesItsShapes) {
    // OpenMM's LocalEnergyMinimizer as a C++ caller gets it moves every atom: what it returns
    // is what the integrator steps from, as any positions set (RigidBodyMinimizer.h says so).
    Cluster cluster = buildCluster(benzene(), 2, 0.62, 3);
    std::unique_ptr<RigidBodyIntegrator> integrator = makeIntegrator(0.001);
    std::unique_ptr<Context> context = makeContext(*cluster.system, *integrator);
    context->setPositions(cluster.positions);
    integrator->step(1);
    const vector<Vec3> stepped = context->getState(State::Positions).getPositions();
    LocalEnergyMinimizer::minimize(*context, 10, 20);
    const vector<Vec3> deformed = context->getState(State::Positions).getPositions();
    ASSERT_GT(maxDistanceChange(stepped, deformed, cluster.molecules), 1e-4);
    integrator->step(2);
    EXPECT_LT(maxDistanceChange(deformed, context->getState(State::Positions).getPositions(), cluster.molecules), 1e-9);
    // The plugin's minimizer keeps the shapes.
    RigidBodyMinimizer::minimize(*context, 10, 5);
    EXPECT_LT(maxDistanceChange(deformed, context->getState(State::Positions).getPositions(), cluster.molecules), 1e-9);
    integrator->step(1);
}

INSTANTIATE_TEST_SUITE_P(AllPlatforms, MinimizerHooks, ::testing::ValuesIn(configsOf("MRattle")), configName);

TEST(MinimizerReference, ReporterSeesEachIterationAndStopsTheSearch) {
    // Any class with OpenMM 8's report() (here the test's own) through ForwardingMinimizationReporter.
    struct Recorder {
        vector<int> iterations;
        vector<double> energies;
        int stopAt = -1;
        bool report(int iteration, const vector<double>& x, const vector<double>& grad, std::map<std::string, double>& args) {
            EXPECT_EQ(x.size(), grad.size());
            EXPECT_EQ(4u, args.size());
            iterations.push_back(iteration);
            energies.push_back(args.at("system energy"));
            return iteration == stopAt;
        }
    } recorder;
    Cluster cluster = buildCluster(benzene(), 2, 0.62, 3);
    MRattleIntegrator integrator(0.001);
    Context context(*cluster.system, integrator, platform("Reference"));
    context.setPositions(cluster.positions);
    ForwardingMinimizationReporter<Recorder> forward(recorder);
    RigidBodyMinimizationReport report = RigidBodyMinimizer::minimize(context, 0.1, 8, &forward);
    EXPECT_EQ(8, report.iterations);
    EXPECT_EQ(vector<int>({0, 1, 2, 3, 4, 5, 6, 7}), recorder.iterations);
    EXPECT_DOUBLE_EQ(report.finalEnergy, recorder.energies.back());
    // Stopped by the reporter: at that iterate, which the Context then holds.
    recorder = Recorder();
    recorder.stopAt = 1;
    context.setPositions(cluster.positions);
    report = RigidBodyMinimizer::minimize(context, 0.1, 0, &forward);
    EXPECT_EQ(2, report.iterations);
    EXPECT_EQ(vector<int>({0, 1}), recorder.iterations);
    EXPECT_NEAR(recorder.energies.back(), context.getState(State::Energy).getPotentialEnergy(), 1e-9 * std::fabs(recorder.energies.back()));
    // What it throws ends the search with an OpenMMException naming it.
    struct Throwing : RigidBodyMinimizationReporter {
        bool report(int, const vector<double>&, const vector<double>&, std::map<std::string, double>&) override {
            throw std::runtime_error("reporter failed");
        }
    } throwing;
    context.setPositions(cluster.positions);
    const std::string message = messageOf([&] { RigidBodyMinimizer::minimize(context, 0.1, 0, &throwing); });
    EXPECT_NE(std::string::npos, message.find("reporter failed")) << message;
}
