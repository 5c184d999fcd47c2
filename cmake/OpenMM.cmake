# Finds the OpenMM install under OPENMM_DIR and defines:
#   OpenMM::OpenMM          imported target (library + include folders)
#   OPENMM_VERSION_STRING   what Platform::getOpenMMVersion() returns for that library ("7.7", "8.5.2")
#   OPENMM_PLUGIN_DIR       the folder holding that install's platform plugins (libOpenMMCPU.so, ...)
# The version is asked of the library itself (a configure-time run), so nothing here
# depends on which version it is: the plugin records it and refuses to load into another.
set(OPENMM_DIR "/usr" CACHE PATH "Where OpenMM is installed (Debian's libopenmm-dev: /usr)")
find_path(OPENMM_INCLUDE_DIR OpenMM.h
    HINTS "${OPENMM_DIR}/include/openmm" "${OPENMM_DIR}/include" NO_DEFAULT_PATH)
find_library(OPENMM_LIBRARY OpenMM
    HINTS "${OPENMM_DIR}/lib" "${OPENMM_DIR}/lib/${CMAKE_LIBRARY_ARCHITECTURE}" NO_DEFAULT_PATH)
if(NOT OPENMM_INCLUDE_DIR OR NOT OPENMM_LIBRARY)
    message(FATAL_ERROR "OpenMM not found under OPENMM_DIR=${OPENMM_DIR}. Install libopenmm-dev or set -DOPENMM_DIR=...")
endif()
get_filename_component(OPENMM_INCLUDE_ROOT "${OPENMM_INCLUDE_DIR}" DIRECTORY)
get_filename_component(OPENMM_LIBRARY_DIR "${OPENMM_LIBRARY}" DIRECTORY)

add_library(OpenMM::OpenMM SHARED IMPORTED)
set_target_properties(OpenMM::OpenMM PROPERTIES
    IMPORTED_LOCATION "${OPENMM_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OPENMM_INCLUDE_DIR};${OPENMM_INCLUDE_ROOT}")

# The version, from the library (the headers carry none).
if(NOT OPENMM_VERSION_STRING OR NOT OPENMM_VERSION_LIBRARY STREQUAL OPENMM_LIBRARY)
    set(probe "${CMAKE_BINARY_DIR}/openmm_version_probe.cpp")
    file(WRITE "${probe}" "#include \"OpenMM.h\"\n#include <iostream>\n"
         "int main() { std::cout << OpenMM::Platform::getOpenMMVersion(); return 0; }\n")
    try_run(run_result compile_result "${CMAKE_BINARY_DIR}/openmm_version_probe" "${probe}"
        CMAKE_FLAGS "-DINCLUDE_DIRECTORIES=${OPENMM_INCLUDE_DIR};${OPENMM_INCLUDE_ROOT}"
        LINK_LIBRARIES "${OPENMM_LIBRARY}"
        LINK_OPTIONS "-Wl,-rpath,${OPENMM_LIBRARY_DIR}"
        CXX_STANDARD 11
        COMPILE_OUTPUT_VARIABLE compile_output
        RUN_OUTPUT_VARIABLE version_output)
    if(NOT compile_result OR NOT run_result EQUAL 0)
        message(FATAL_ERROR "Could not ask ${OPENMM_LIBRARY} for its version:\n${compile_output}\n${version_output}")
    endif()
    string(STRIP "${version_output}" version_output)
    set(OPENMM_VERSION_STRING "${version_output}" CACHE INTERNAL "OpenMM version of OPENMM_LIBRARY")
    set(OPENMM_VERSION_LIBRARY "${OPENMM_LIBRARY}" CACHE INTERNAL "The library OPENMM_VERSION_STRING was read from")
endif()

# The platform plugins of that install: <libdir>/plugins (OpenMM's own layout) or
# <libdir>/openmm/plugins (Debian's).
if(NOT OPENMM_PLUGIN_DIR)
    foreach(candidate "${OPENMM_LIBRARY_DIR}/plugins" "${OPENMM_LIBRARY_DIR}/openmm/plugins")
        file(GLOB plugin_libraries "${candidate}/libOpenMM*${CMAKE_SHARED_LIBRARY_SUFFIX}")
        if(plugin_libraries)
            set(OPENMM_PLUGIN_DIR "${candidate}" CACHE PATH "OpenMM's platform plugin folder (libOpenMMCPU.so, ...)")
            break()
        endif()
    endforeach()
endif()
if(NOT OPENMM_PLUGIN_DIR)
    message(WARNING "No OpenMM platform plugins found next to ${OPENMM_LIBRARY}: only the Reference platform will be "
                    "available to the tests. Set -DOPENMM_PLUGIN_DIR=... to name the folder.")
    set(OPENMM_PLUGIN_DIR "${OPENMM_LIBRARY_DIR}/plugins")
endif()
message(STATUS "OpenMM ${OPENMM_VERSION_STRING}: ${OPENMM_LIBRARY}, plugins in ${OPENMM_PLUGIN_DIR}")
