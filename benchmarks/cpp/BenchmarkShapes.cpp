#include "BenchmarkShapes.h"
#include <cmath>

namespace MRattleBenchmark {

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

} // namespace MRattleBenchmark
