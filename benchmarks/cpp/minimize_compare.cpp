// RigidBodyMinimizer against OpenMM's LocalEnergyMinimizer on one System from the same start (the rigid
// integrator's exact shapes); ./benchmarks/run.sh validate-minimization writes the inputs. One CSV row per minimizer.
//   minimize_compare SYSTEM.xml POSITIONS.txt BODIES.txt PLATFORM TOLERANCE NAME [REPEATS=3]
// POSITIONS.txt: "x y z" (nm) per particle; BODIES.txt: particle indices per body, none: every molecule.
// OpenMM 7.7's LocalEnergyMinimizer reports no iteration count: an untimed second run counts them from the
// positions it sets (a trial point off the current line search's line starts a new iteration).
#include "MRattleBuildInfo.h"
#include "MRattleIntegrator.h"
#include "RigidBodyMinimizer.h"
#include "OpenMM.h"
#include "openmm/internal/ContextImpl.h"
#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

extern "C" void registerMRattleReferenceKernelFactories();

using namespace OpenMM;
using namespace MRattlePlugin;
using std::vector;

namespace {

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

using Clock = std::chrono::steady_clock;

/**
 * RMS over particles of the force projected on the allowed motion: rigid motion for each
 * body (unit masses), the constraints' tangent space for the other particles (each
 * connected cluster of constraints solved on its own).
 */
double rmsGeneralizedForce(const System& system, const vector<Vec3>& x, const vector<Vec3>& f,
                           const vector<vector<int> >& bodies) {
    const int n = system.getNumParticles();
    vector<int> bodyOf(n, -1);
    for (size_t b = 0; b < bodies.size(); b++)
        for (int i : bodies[b])
            bodyOf[i] = b;
    double sum = 0;
    for (const vector<int>& body : bodies) {
        Eigen::Vector3d c = Eigen::Vector3d::Zero(), F = Eigen::Vector3d::Zero(), tau = Eigen::Vector3d::Zero();
        for (int i : body)
            c += Eigen::Vector3d(x[i][0], x[i][1], x[i][2]) / body.size();
        Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
        for (int i : body) {
            const Eigen::Vector3d r = Eigen::Vector3d(x[i][0], x[i][1], x[i][2]) - c, fi(f[i][0], f[i][1], f[i][2]);
            F += fi;
            tau += r.cross(fi);
            inertia += r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose();
        }
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> principal(inertia);
        for (int k = 0; k < 3; k++)
            if (principal.eigenvalues()[k] > 1e-9 * principal.eigenvalues()[2])
                sum += std::pow(principal.eigenvectors().col(k).dot(tau), 2) / principal.eigenvalues()[k];
        sum += F.squaredNorm() / body.size();
    }
    // The constraints among particles outside bodies, projected out together: one dense solve
    // (constraints of different clusters share no particle, so A A^T is block diagonal and the
    // solution is each cluster's own; no cluster search is needed).
    vector<int> p1, p2;
    for (int c = 0; c < system.getNumConstraints(); c++) {
        int a, b;
        double d;
        system.getConstraintParameters(c, a, b, d);
        if (bodyOf[a] < 0 && bodyOf[b] < 0 && system.getParticleMass(a) != 0 && system.getParticleMass(b) != 0) {
            p1.push_back(a);
            p2.push_back(b);
        }
    }
    const int m = p1.size();
    vector<Vec3> projected(n), u(m);
    for (int i = 0; i < n; i++)
        projected[i] = system.getParticleMass(i) == 0 || bodyOf[i] >= 0 ? Vec3() : f[i];
    for (int k = 0; k < m; k++)
        u[k] = (x[p2[k]] - x[p1[k]]) / std::sqrt((x[p2[k]] - x[p1[k]]).dot(x[p2[k]] - x[p1[k]]));
    // Row k of A: -u_k on p1, +u_k on p2. Solve (A A^T) l = A f, then f -= A^T l.
    Eigen::MatrixXd AAt = Eigen::MatrixXd::Zero(m, m);
    Eigen::VectorXd Af(m);
    for (int a = 0; a < m; a++) {
        Af[a] = u[a].dot(f[p2[a]] - f[p1[a]]);
        for (int b = 0; b < m; b++)
            AAt(a, b) = u[a].dot(u[b]) * ((p1[a] == p1[b]) - (p1[a] == p2[b]) - (p2[a] == p1[b]) + (p2[a] == p2[b]));
    }
    const Eigen::VectorXd l = AAt.ldlt().solve(Af);
    for (int k = 0; k < m; k++) {
        projected[p1[k]] += u[k] * l[k];
        projected[p2[k]] -= u[k] * l[k];
    }
    for (int i = 0; i < n; i++)
        sum += projected[i].dot(projected[i]);
    return std::sqrt(sum / n);
}

double maxShapeChange(const vector<Vec3>& a, const vector<Vec3>& b, const vector<vector<int> >& bodies) {
    double worst = 0;
    for (const vector<int>& body : bodies)
        for (size_t i = 0; i < body.size(); i++)
            for (size_t j = i + 1; j < body.size(); j++) {
                const Vec3 da = a[body[i]] - a[body[j]], db = b[body[i]] - b[body[j]];
                worst = std::max(worst, std::fabs(std::sqrt(da.dot(da)) - std::sqrt(db.dot(db))));
            }
    return worst;
}

struct Row {
    std::string minimizer;
    int iterations = 0, evaluations = 0;
    double before = 0, after = 0, rms = 0, shape = 0, seconds = 0;
};

void print(const std::string& name, const Row& r, const std::string& note) {
    std::printf("%s,%s,%d,%d,%.6f,%.6f,%.4f,%.3g,%.3f,%s\n", name.c_str(), r.minimizer.c_str(), r.iterations,
                r.evaluations, r.before, r.after, r.rms, r.shape, r.seconds, note.c_str());
}

} // namespace

int main(int argc, char** argv) {
    if (argc != 7 && argc != 8) {
        std::cerr << "usage: minimize_compare SYSTEM.xml POSITIONS.txt BODIES.txt PLATFORM TOLERANCE NAME [REPEATS]\n";
        return 2;
    }
    try {
        setenv("OPENMM_PLUGIN_DIR", MRATTLE_OPENMM_PLUGIN_DIR, 0);
        Platform::loadPluginsFromDirectory(Platform::getDefaultPluginsDirectory());
        registerMRattleReferenceKernelFactories();
        std::ifstream systemFile(argv[1]);
        std::unique_ptr<System> system(XmlSerializer::deserialize<System>(systemFile));
        vector<Vec3> raw;
        std::ifstream positionsFile(argv[2]);
        double px, py, pz;
        while (positionsFile >> px >> py >> pz)
            raw.push_back(Vec3(px, py, pz));
        MRattleIntegrator rigidIntegrator(0.001);
        std::ifstream bodiesFile(argv[3]);
        std::string line;
        while (std::getline(bodiesFile, line)) {
            std::istringstream fields(line);
            vector<int> body;
            int i;
            while (fields >> i)
                body.push_back(i);
            if (!body.empty())
                rigidIntegrator.addRigidBody(body);
        }
        Platform& platform = Platform::getPlatformByName(argv[4]);
        std::map<std::string, std::string> properties;
        if (platform.getName() == "CPU")
            properties["Threads"] = "1";
        const double tolerance = std::stod(argv[5]);
        const std::string name = argv[6];
        const int repeats = argc == 8 ? std::max(1, std::atoi(argv[7])) : 3;

        // The rigid minimizer, from the exact shapes the integrator takes.
        Context rigid(*system, rigidIntegrator, platform, properties);
        rigid.setPositions(raw);
        const vector<Vec3> start = rigid.getState(State::Positions).getPositions();
        const vector<vector<int> > bodies = rigidIntegrator.getBodiesInEffect();
        VerletIntegrator verlet(0.001);
        verlet.setConstraintTolerance(rigidIntegrator.getConstraintTolerance());
        Context flexible(*system, verlet, platform, properties);
        // Each minimizer runs `repeats` times from the start, alternating with the other, and
        // the fastest run of each counts: a shared machine's load then biases neither.
        Row mine, openmm;
        mine.minimizer = "RigidBodyMinimizer";
        openmm.minimizer = "LocalEnergyMinimizer";
        mine.seconds = openmm.seconds = 1e300;
        State end = rigid.getState(State::Energy), flexibleEnd = end;
        RigidBodyMinimizationReport report;
        for (int r = 0; r < repeats; r++) {
            rigid.setPositions(start);
            auto t0 = Clock::now();
            report = RigidBodyMinimizer::minimize(rigid, tolerance);
            mine.seconds = std::min(mine.seconds, std::chrono::duration<double>(Clock::now() - t0).count());
            // LocalEnergyMinimizer on the same System with OpenMM's constraints (SETTLE, CCMA), same start.
            flexible.setPositions(start);
            openmm.before = flexible.getState(State::Energy).getPotentialEnergy();
            t0 = Clock::now();
            LocalEnergyMinimizer::minimize(flexible, tolerance);
            openmm.seconds = std::min(openmm.seconds, std::chrono::duration<double>(Clock::now() - t0).count());
        }
        end = rigid.getState(State::Positions | State::Forces | State::Energy);
        mine.iterations = report.iterations;
        mine.evaluations = report.evaluations;
        mine.before = report.initialEnergy;
        mine.after = end.getPotentialEnergy();
        mine.rms = rmsGeneralizedForce(*system, end.getPositions(), end.getForces(), bodies);
        mine.shape = maxShapeChange(start, end.getPositions(), bodies);
        end = flexible.getState(State::Positions | State::Forces | State::Energy);
        openmm.after = end.getPotentialEnergy();
        // Its bodies are only those its constraints hold rigid: the projection uses them as constraints.
        openmm.rms = rmsGeneralizedForce(*system, end.getPositions(), end.getForces(), {});
        openmm.shape = maxShapeChange(start, end.getPositions(), bodies);

        CountingVerletIntegrator counting(0.001);
        counting.setConstraintTolerance(rigidIntegrator.getConstraintTolerance());
        Context counted(*system, counting, platform, properties);
        counted.setPositions(start);
        counting.reset();
        LocalEnergyMinimizer::minimize(counted, tolerance);
        openmm.iterations = counting.iterations;
        openmm.evaluations = counting.evaluations;
        const double countedEnergy = counted.getState(State::Energy).getPotentialEnergy();
        const bool same = std::fabs(countedEnergy - openmm.after) <= 1e-9 * std::fabs(openmm.after) + 1e-9;

        std::printf("case,minimizer,iterations,evaluations,energy_before,energy_after,rms_force,max_shape_change,"
                    "seconds,note\n");
        print(name, mine, "");
        print(name, openmm, same ? "iterations counted in a second run that ended at the same energy"
                                 : "iterations counted in a second run that ended ELSEWHERE: count not valid");
        if (mine.iterations > 0 && openmm.iterations > 0)
            std::printf("# %s: cost per iteration, RigidBodyMinimizer / LocalEnergyMinimizer = %.3f; per evaluation "
                        "%.3f\n", name.c_str(), (mine.seconds / mine.iterations) / (openmm.seconds / openmm.iterations),
                        (mine.seconds / mine.evaluations) / (openmm.seconds / openmm.evaluations));
    } catch (const std::exception& e) {
        std::cerr << "minimize_compare: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
