#ifndef MRATTLE_BENCHMARK_SHAPES_H_
#define MRATTLE_BENCHMARK_SHAPES_H_

#include <array>
#include <vector>

namespace MRattleBenchmark {

/** A rigid body shape: sites (nm) about the centre of mass, and masses (amu). */
struct Shape {
    std::vector<std::array<double, 3> > sites;
    std::vector<double> masses;
};

/**
 * A non-planar, non-linear body of k atoms. k = 5 is a tetrahedral CX4 (methane-like,
 * C-H 0.109 nm); k = 3 is a bent triatomic; otherwise k atoms on a helix of radius
 * 0.15-0.3 nm with mixed masses (an irregular, asymmetric body).
 */
Shape bodyShape(int k);

} // namespace MRattleBenchmark

#endif
