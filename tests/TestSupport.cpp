#include "TestSupport.h"
#include <cmath>
#include <mutex>

extern "C" void registerMRattleReferenceKernelFactories();

using namespace OpenMM;

namespace MRattleTest {

void loadPlugins() {
    static std::once_flag once;
    std::call_once(once, [] {
        Platform::loadPluginsFromDirectory(Platform::getDefaultPluginsDirectory());
        registerMRattleReferenceKernelFactories();
    });
}

Platform& platform(const std::string& name) {
    loadPlugins();
    return Platform::getPlatformByName(name);
}

Molecule benzene() {
    Molecule m;
    const double cc = 0.1397, ch = 0.1084;
    for (int k = 0; k < 6; k++) {
        double angle = k * M_PI / 3;
        m.sites.push_back(Vec3(cc * std::cos(angle), cc * std::sin(angle), 0));
        m.masses.push_back(12.011);
        m.charges.push_back(-0.115);
        m.sigmas.push_back(0.355);
        m.epsilons.push_back(0.29288);
    }
    for (int k = 0; k < 6; k++) {
        double angle = k * M_PI / 3;
        m.sites.push_back(Vec3((cc + ch) * std::cos(angle), (cc + ch) * std::sin(angle), 0));
        m.masses.push_back(1.008);
        m.charges.push_back(0.115);
        m.sigmas.push_back(0.242);
        m.epsilons.push_back(0.12552);
    }
    for (int k = 0; k < 6; k++) {
        m.bonds.push_back({k, (k + 1) % 6});
        m.bonds.push_back({k, k + 6});
    }
    return m;
}

double maxDistanceChange(const std::vector<Vec3>& a, const std::vector<Vec3>& b,
                         const std::vector<std::vector<int> >& bodies) {
    double worst = 0;
    for (const auto& body : bodies)
        for (size_t i = 0; i < body.size(); i++)
            for (size_t j = i + 1; j < body.size(); j++) {
                Vec3 da = a[body[i]] - a[body[j]], db = b[body[i]] - b[body[j]];
                worst = std::max(worst, std::fabs(std::sqrt(da.dot(da)) - std::sqrt(db.dot(db))));
            }
    return worst;
}

} // namespace MRattleTest
