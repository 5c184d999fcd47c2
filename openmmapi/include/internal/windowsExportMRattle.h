#ifndef OPENMM_WINDOWS_EXPORT_MRATTLE_H_
#define OPENMM_WINDOWS_EXPORT_MRATTLE_H_

/* Symbol visibility of the plugin's public API, following OpenMM's convention. */
#if defined(_MSC_VER)
    #if defined(MRATTLE_BUILDING_SHARED_LIBRARY)
        #define OPENMM_EXPORT_MRATTLE __declspec(dllexport)
    #else
        #define OPENMM_EXPORT_MRATTLE __declspec(dllimport)
    #endif
#else
    #define OPENMM_EXPORT_MRATTLE __attribute__((visibility("default")))
#endif

#endif
