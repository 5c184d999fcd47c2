#include "MRattleIntegrator.h"
#include "MRattleBussiIntegratorProxy.h"
#include "MRattleLangevinIntegratorProxy.h"
#include "MRattleNoseHooverIntegratorProxy.h"
#include "RigidBodyIntegratorProxy.h"
#include "RigidSplittingIntegrator.h"
#include "openmm/serialization/SerializationProxy.h"
#include "internal/windowsExportMRattle.h"

// The proxies are registered when the library is loaded, as OpenMM does for its own
// plugins: from DllMain on Windows, from a constructor function elsewhere.
#if defined(WIN32)
#include <windows.h>
extern "C" OPENMM_EXPORT_MRATTLE void registerMRattleSerializationProxies();
BOOL WINAPI DllMain(HANDLE hModule, DWORD reason, LPVOID reserved) {
    if (reason == DLL_PROCESS_ATTACH)
        registerMRattleSerializationProxies();
    return TRUE;
}
#else
extern "C" OPENMM_EXPORT_MRATTLE void __attribute__((constructor)) registerMRattleSerializationProxies();
#endif

using namespace MRattlePlugin;
using namespace OpenMM;

/** Register the XML proxy of a RigidBodyIntegrator subclass under its class name: one line per integrator. */
#define MRATTLE_REGISTER_PROXY(CLASS) \
    SerializationProxy::registerProxy(typeid(CLASS), new RigidBodyIntegratorProxy<CLASS>(#CLASS))

extern "C" OPENMM_EXPORT_MRATTLE void registerMRattleSerializationProxies() {
    MRATTLE_REGISTER_PROXY(MRattleIntegrator);
    MRATTLE_REGISTER_PROXY(RigidSplittingIntegrator);
    MRATTLE_REGISTER_PROXY(MRattleLangevinIntegrator);
    MRATTLE_REGISTER_PROXY(MRattleNoseHooverIntegrator);
    MRATTLE_REGISTER_PROXY(MRattleBussiIntegrator);
}
