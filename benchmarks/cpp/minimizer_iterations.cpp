// LocalEnergyMinimizer's iterations and evaluations on one System, which OpenMM 7.7 does not report
// (./benchmarks/run.sh validate-minimization runs it):
//   minimizer_iterations SYSTEM.xml POSITIONS.txt PLATFORM TOLERANCE CONSTRAINT_TOLERANCE
// POSITIONS.txt: "x y z" (nm) per particle. Prints "iterations evaluations final_energy": counted from the
// positions the minimizer sets (a trial point off the current line search's line starts a new iteration).
#include "MRattleBuildInfo.h"
#include "OpenMM.h"
#include "openmm/internal/ContextImpl.h"
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <string>

using namespace OpenMM;
using std::vector;

/** A VerletIntegrator that counts LocalEnergyMinimizer's iterations and evaluations from its setPositions calls. */
class CountingVerletIntegrator : public VerletIntegrator {
public:
    explicit CountingVerletIntegrator(double stepSize) : VerletIntegrator(stepSize) {}
    int iterations = 0, evaluations = 0;
    void reset() {
        iterations = evaluations = 0;
        base.clear();
        previous.clear();
    }

protected:
    void stateChanged(State::DataType changed) override {
        VerletIntegrator::stateChanged(changed);
        if (changed != State::Positions)
            return;
        vector<Vec3> p;
        context->getPositions(p);
        evaluations++;
        if (previous.empty()) {
            base = previous = p;
            return;
        }
        double step = 0, along = 0, lengthNew = 0, lengthOld = 0;
        for (size_t i = 0; i < p.size(); i++) {
            step += (p[i] - previous[i]).dot(p[i] - previous[i]);
            along += (p[i] - base[i]).dot(previous[i] - base[i]);
            lengthNew += (p[i] - base[i]).dot(p[i] - base[i]);
            lengthOld += (previous[i] - base[i]).dot(previous[i] - base[i]);
        }
        if (step == 0)
            base = p;  // the same point again: a new search starts here
        else if (lengthOld == 0)
            iterations++;  // the first trial of a line search from base
        else if (!(along > (1 - 1e-8) * std::sqrt(lengthNew * lengthOld))) {
            iterations++;  // off the line: a new search from the last accepted point
            base = previous;
        }
        previous = p;
    }

private:
    vector<Vec3> base, previous;
};

int main(int argc, char** argv) {
    if (argc != 6) {
        std::cerr << "usage: minimizer_iterations SYSTEM.xml POSITIONS.txt PLATFORM TOLERANCE CONSTRAINT_TOLERANCE\n";
        return 2;
    }
    try {
        setenv("OPENMM_PLUGIN_DIR", MRATTLE_OPENMM_PLUGIN_DIR, 0);
        Platform::loadPluginsFromDirectory(Platform::getDefaultPluginsDirectory());
        std::ifstream systemFile(argv[1]), positionsFile(argv[2]);
        std::unique_ptr<System> system(XmlSerializer::deserialize<System>(systemFile));
        vector<Vec3> positions;
        for (double x, y, z; positionsFile >> x >> y >> z;)
            positions.push_back(Vec3(x, y, z));
        Platform& platform = Platform::getPlatformByName(argv[3]);
        std::map<std::string, std::string> properties;
        if (platform.getName() == "CPU")
            properties["Threads"] = "1";
        CountingVerletIntegrator counting(0.001);
        counting.setConstraintTolerance(std::stod(argv[5]));
        Context context(*system, counting, platform, properties);
        context.setPositions(positions);
        counting.reset();
        LocalEnergyMinimizer::minimize(context, std::stod(argv[4]));
        std::printf("%d %d %.17g\n", counting.iterations, counting.evaluations,
                    context.getState(State::Energy).getPotentialEnergy());
    } catch (const std::exception& e) {
        std::cerr << "minimizer_iterations: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
