#include "internal/FiniteValues.h"
#include "openmm/OpenMMException.h"
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;

void FiniteValues::require(const std::vector<Vec3>& values, const std::string& what) {
    for (size_t i = 0; i < values.size(); i++)
        if (!std::isfinite(values[i][0] + values[i][1] + values[i][2]))
            throw OpenMMException("the " + what + " of particle " + std::to_string(i) + " is not finite");
}
