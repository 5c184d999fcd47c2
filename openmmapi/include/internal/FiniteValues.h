#ifndef MRATTLE_FINITE_VALUES_H_
#define MRATTLE_FINITE_VALUES_H_

#include "openmm/Vec3.h"
#include "internal/windowsExportMRattle.h"
#include <string>
#include <vector>

namespace MRattlePlugin {
namespace FiniteValues {

/** Throw an OpenMMException naming the first particle whose value (`what`: "position", ...) is not finite. */
OPENMM_EXPORT_MRATTLE void require(const std::vector<OpenMM::Vec3>& values, const std::string& what);

} // namespace FiniteValues
} // namespace MRattlePlugin

#endif
