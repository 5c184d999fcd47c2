/*
 * Micro-benchmarks of the numerical core, per body of k atoms (k = 3, 5, 12, 30):
 *  - MRattlePositionUpdate: RigidBodyMath::driftAndResetBody, what the kernels do to a
 *    body's positions each step: drift x + h v, M-RATTLE position reset (the rotation
 *    solve), v = (x_new - x) / h. MRattlePositionUpdateFourAtATime: the same through
 *    kickDriftAndResetBodies, as the kernels call it (rotation solves in SIMD lanes).
 *  - SplittingPositionUpdate: the splitting baseline's position half step for the same
 *    body (momenta from velocities, principal frame, free rotor, new x and v).
 *  - ProjectBodyVelocities: the velocity reset (RATTLE's velocity step), shared by both.
 *  - SolveResetRotation, PrincipalFrame, FreeRotorStep: the O(1) parts alone.
 * Each iteration processes a batch of bodies in one global array, as the kernel does;
 * the "per_body" counter is the time per body. Forces are zero: the bodies rotate freely
 * at about 5 rad/ps with h = 2 fs, a typical thermal rotation per step.
 */
#include "BenchmarkShapes.h"
#include "mrattle/RigidBodyMath.h"
#include "mrattle/RigidBodyRotor.h"
#include <benchmark/benchmark.h>
#include <random>
#include <utility>
#include <vector>

using namespace MRattlePlugin;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

const int BatchSize = 256;
const double StepSize = 0.002;

/** BatchSize copies of the k-atom body, randomly oriented, with rigid velocities. */
struct Batch {
    int atomsPerBody;
    std::vector<int> atoms;
    std::vector<double> masses, positions, velocities, scratchPositions, scratchVelocities, forces;
    double bodyMass = 0;

    explicit Batch(int k) : atomsPerBody(k) {
        MRattleBenchmark::Shape shape = MRattleBenchmark::bodyShape(k);
        std::mt19937_64 random(k);
        std::normal_distribution<double> gaussian(0.0, 1.0);
        for (double m : shape.masses)
            bodyMass += m;
        for (int b = 0; b < BatchSize; b++) {
            Vector3d axis(gaussian(random), gaussian(random), gaussian(random));
            Matrix3d orientation = RigidBodyMath::rotationFromVector(axis);
            Vector3d center(b % 8, (b / 8) % 8, b / 64);
            Vector3d V(gaussian(random), gaussian(random), gaussian(random));
            Vector3d omega = 5.0 * Vector3d(gaussian(random), gaussian(random), gaussian(random)).normalized();
            for (int j = 0; j < k; j++) {
                Vector3d a = orientation * Vector3d(shape.sites[j][0], shape.sites[j][1], shape.sites[j][2]);
                Vector3d x = center + a, v = V + omega.cross(a);
                atoms.push_back(b * k + j);
                masses.push_back(shape.masses[j]);
                for (int d = 0; d < 3; d++) {
                    positions.push_back(x(d));
                    velocities.push_back(v(d));
                }
            }
        }
        scratchPositions = positions;
        scratchVelocities = velocities;
        forces.assign(positions.size(), 0.0);
    }
    RigidBodyMath::BodyView view(int b) const {
        return RigidBodyMath::BodyView{atoms.data() + b * atomsPerBody, atomsPerBody, masses.data(), bodyMass, false};
    }
};

void perBodyCounter(benchmark::State& state) {
    state.counters["per_body"] =
        benchmark::Counter(BatchSize, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void MRattlePositionUpdate(benchmark::State& state) {
    Batch batch(state.range(0));
    for (auto _ : state) {
        for (int b = 0; b < BatchSize; b++) {
            RigidBodyMath::RotationSolve solve = RigidBodyMath::driftAndResetBody(
                batch.view(b), StepSize, batch.positions.data(), batch.velocities.data(),
                batch.scratchPositions.data());
            benchmark::DoNotOptimize(solve.iterations);
        }
        std::swap(batch.positions, batch.scratchPositions);
    }
    perBodyCounter(state);
}

void MRattlePositionUpdateFourAtATime(benchmark::State& state) {
    // What the CPU and Reference kernels run: RigidBodyMath::kickDriftAndResetBodies, whose
    // rotation solves share SIMD lanes four bodies at a time (no kick here).
    Batch batch(state.range(0));
    std::vector<RigidBodyMath::BodyView> views;
    for (int b = 0; b < BatchSize; b++)
        views.push_back(batch.view(b));
    const RigidBodyMath::Kick noKick;
    for (auto _ : state) {
        int failed = RigidBodyMath::kickDriftAndResetBodies(views.data(), BatchSize, noKick, StepSize,
                                                            batch.positions.data(), batch.velocities.data(),
                                                            batch.scratchPositions.data(),
                                                            batch.scratchVelocities.data());
        benchmark::DoNotOptimize(failed);
        std::swap(batch.positions, batch.scratchPositions);
        std::swap(batch.velocities, batch.scratchVelocities);
    }
    perBodyCounter(state);
}

void SplittingPositionUpdate(benchmark::State& state) {
    Batch batch(state.range(0));
    for (auto _ : state) {
        for (int b = 0; b < BatchSize; b++)
            RigidBodyRotor::positionStep(batch.view(b), batch.positions.data(), batch.velocities.data(),
                                         batch.forces.data(), StepSize, batch.scratchPositions.data(),
                                         batch.scratchVelocities.data());
        std::swap(batch.positions, batch.scratchPositions);
        std::swap(batch.velocities, batch.scratchVelocities);
        benchmark::ClobberMemory();
    }
    perBodyCounter(state);
}

void ProjectBodyVelocities(benchmark::State& state) {
    Batch batch(state.range(0));
    for (auto _ : state) {
        for (int b = 0; b < BatchSize; b++)
            RigidBodyMath::projectBodyVelocities(batch.view(b), batch.positions.data(), batch.velocities.data());
        benchmark::ClobberMemory();
    }
    perBodyCounter(state);
}

/** J and Y of one thermal M-RATTLE step of each body of the batch. */
void resetInputs(const Batch& batch, std::vector<Matrix3d>& J, std::vector<Matrix3d>& Y) {
    for (int b = 0; b < BatchSize; b++) {
        RigidBodyMath::BodyView body = batch.view(b);
        std::vector<double> drifted = batch.positions;
        for (size_t i = 0; i < drifted.size(); i++)
            drifted[i] += StepSize * batch.velocities[i];
        Vector3d oldCenter = RigidBodyMath::centerOfMass(body, batch.positions.data());
        Vector3d newCenter = RigidBodyMath::centerOfMass(body, drifted.data());
        Matrix3d j = Matrix3d::Zero(), y = Matrix3d::Zero();
        for (int k = 0; k < body.numAtoms; k++) {
            int atom = body.atoms[k];
            Vector3d a = Eigen::Map<const Vector3d>(&batch.positions[3 * atom]) - oldCenter;
            Vector3d yk = Eigen::Map<const Vector3d>(&drifted[3 * atom]) - newCenter;
            j += body.masses[atom] * a * a.transpose();
            y += body.masses[atom] * yk * a.transpose();
        }
        J.push_back(j);
        Y.push_back(y);
    }
}

void SolveResetRotation(benchmark::State& state) {
    Batch batch(state.range(0));
    std::vector<Matrix3d> J, Y;
    resetInputs(batch, J, Y);
    int iterations = 0;
    for (auto _ : state)
        for (int b = 0; b < BatchSize; b++) {
            RigidBodyMath::RotationSolve solve = RigidBodyMath::solveResetRotation(J[b], Y[b]);
            iterations += solve.iterations;
            benchmark::DoNotOptimize(solve.rotation);
        }
    perBodyCounter(state);
    state.counters["newton_iterations"] = (double) iterations / (BatchSize * state.iterations());
}

void PrincipalFrame(benchmark::State& state) {
    Batch batch(state.range(0));
    std::vector<Matrix3d> J, Y;
    resetInputs(batch, J, Y);
    for (auto _ : state)
        for (int b = 0; b < BatchSize; b++) {
            RigidBodyRotor::PrincipalFrame frame = RigidBodyRotor::principalFrame(J[b]);
            benchmark::DoNotOptimize(frame);
        }
    perBodyCounter(state);
}

void FreeRotorStep(benchmark::State& state) {
    Batch batch(state.range(0));
    std::vector<Matrix3d> J, Y;
    resetInputs(batch, J, Y);
    std::vector<RigidBodyRotor::PrincipalFrame> frames;
    for (const Matrix3d& j : J)
        frames.push_back(RigidBodyRotor::principalFrame(j));
    Vector3d momentum(0.5, -1.0, 2.0);
    for (auto _ : state)
        for (int b = 0; b < BatchSize; b++) {
            Vector3d pi = momentum;
            Matrix3d R = RigidBodyRotor::freeRotorStep(frames[b].moments, pi, StepSize, false);
            benchmark::DoNotOptimize(R);
        }
    perBodyCounter(state);
}

} // namespace

BENCHMARK(MRattlePositionUpdate)->ArgName("k")->Arg(3)->Arg(5)->Arg(12)->Arg(30);
BENCHMARK(MRattlePositionUpdateFourAtATime)->ArgName("k")->Arg(3)->Arg(5)->Arg(12)->Arg(30);
BENCHMARK(SplittingPositionUpdate)->ArgName("k")->Arg(3)->Arg(5)->Arg(12)->Arg(30);
BENCHMARK(ProjectBodyVelocities)->ArgName("k")->Arg(3)->Arg(5)->Arg(12)->Arg(30);
BENCHMARK(SolveResetRotation)->ArgName("k")->Arg(3)->Arg(5)->Arg(12)->Arg(30);
BENCHMARK(PrincipalFrame)->ArgName("k")->Arg(5);
BENCHMARK(FreeRotorStep)->ArgName("k")->Arg(5);

BENCHMARK_MAIN();
