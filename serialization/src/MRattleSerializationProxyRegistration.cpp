#include "MRattleIntegrator.h"
#include "MRattleIntegratorProxy.h"
#include "MRattleLangevinIntegrator.h"
#include "MRattleLangevinIntegratorProxy.h"
#include "RigidSplittingIntegrator.h"
#include "RigidSplittingIntegratorProxy.h"
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

extern "C" OPENMM_EXPORT_MRATTLE void registerMRattleSerializationProxies() {
    SerializationProxy::registerProxy(typeid(MRattleIntegrator), new MRattleIntegratorProxy());
    SerializationProxy::registerProxy(typeid(RigidSplittingIntegrator), new RigidSplittingIntegratorProxy());
    SerializationProxy::registerProxy(typeid(MRattleLangevinIntegrator), new MRattleLangevinIntegratorProxy());
}
