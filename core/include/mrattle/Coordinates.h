#ifndef MRATTLE_COORDINATES_H_
#define MRATTLE_COORDINATES_H_

#include <Eigen/Dense>

namespace MRattlePlugin {

/** Atom `atom` of a 3N-double coordinate array (x0,y0,z0,x1,...) as an Eigen vector, in place. */
inline Eigen::Map<const Eigen::Vector3d> point(const double* array, int atom) {
    return Eigen::Map<const Eigen::Vector3d>(array + 3 * atom);
}

inline Eigen::Map<Eigen::Vector3d> point(double* array, int atom) {
    return Eigen::Map<Eigen::Vector3d>(array + 3 * atom);
}

} // namespace MRattlePlugin

#endif
