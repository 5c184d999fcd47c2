# liblbfgs, the L-BFGS of the rigid-body minimizer (RigidBodyMinimizer): the code OpenMM's own
# LocalEnergyMinimizer embeds. Debian: liblbfgs-dev (scripts/install-deps.sh installs it).
find_path(LBFGS_INCLUDE_DIR lbfgs.h)
find_library(LBFGS_LIBRARY lbfgs)
if(NOT LBFGS_INCLUDE_DIR OR NOT LBFGS_LIBRARY)
    message(FATAL_ERROR "liblbfgs not found (lbfgs.h: ${LBFGS_INCLUDE_DIR}, library: ${LBFGS_LIBRARY}). "
                        "Install Debian's liblbfgs-dev (./scripts/install-deps.sh), or pass "
                        "-DLBFGS_INCLUDE_DIR=<dir with lbfgs.h> -DLBFGS_LIBRARY=<path of liblbfgs>.")
endif()
message(STATUS "liblbfgs: ${LBFGS_LIBRARY}")
add_library(MRattleLBFGS INTERFACE)
target_include_directories(MRattleLBFGS INTERFACE "${LBFGS_INCLUDE_DIR}")
target_link_libraries(MRattleLBFGS INTERFACE "${LBFGS_LIBRARY}")
