/*
 * The CUDA program check: every device program of the plugin compiled through NVRTC the way
 * OpenMM's CUDA platform compiles it, on a machine without a GPU. The text is built as
 * CudaContext::createModule builds it (OpenMM 8.5.2): the context's defines, the real/mixed
 * typedefs, CudaKernelSources::common, the program's defines, CudaKernelSources::vectorOps
 * (compileProgram's prefix) and the program; options "-arch=compute_<arch> --use_fast_math".
 * The programs and their defines are the plugin's own (CommonRigidBodyState::programSource
 * and programDefines). Only the context's defines are copied here from
 * CudaContext's constructor (a CUDA driver >= 9.0, a rectangular box): OpenMM keeps them private.
 *
 * usage: cuda_program_check OUTPUT_DIR [ARCH]   (ARCH: 90 for compute_90 unless given)
 * Prints, for each program and precision, NVRTC's diagnostics in the plugin's code (those in
 * OpenMM's prelude only counted); writes OUTPUT_DIR/<program>-<precision>.{cu,log,ptx} (the
 * PTX for `ptxas -arch=sm_<arch> -v`: registers and spills); exits 1 if any program fails.
 */
#include "CommonMRattleKernelSources.h"
#include "CommonRigidBodyState.h"
#include <algorithm>
#include <fstream>
#include <iostream>
#include <map>
#include <nvrtc.h>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace OpenMM {
/**
 * The two prelude strings of libOpenMMCUDA (exported). OpenMM generates CudaKernelSources.h
 * while building and its install rule globs for it at configure time, before it exists, so
 * an installed OpenMM 8.5.2 lacks the header: the members used here are declared as it declares them.
 */
class CudaKernelSources {
public:
    static const std::string common;
    static const std::string vectorOps;
};
} // namespace OpenMM

using namespace MRattlePlugin;
using OpenMM::CudaKernelSources;
using Defines = std::map<std::string, std::string>;

namespace {

struct Precision {
    const char* name;
    bool useDouble, useMixed;
};

/** CudaContext's compilationDefines for this precision (OpenMM 8.5.2, CudaContext.cpp). */
Defines contextDefines(const Precision& p) {
    Defines d;
    d["SYNC_WARPS"] = "__syncwarp();";
    d["SHFL(var, srcLane)"] = "__shfl_sync(0xffffffff, var, srcLane);";
    d["BALLOT(var)"] = "__ballot_sync(0xffffffff, var);";
    const bool doubleMixed = p.useDouble || p.useMixed;
    if (p.useDouble)
        d["USE_DOUBLE_PRECISION"] = "1";
    if (p.useMixed)
        d["USE_MIXED_PRECISION"] = "1";
    for (const char* n : {"2", "3", "4"}) {
        d[std::string("make_real") + n] = std::string(p.useDouble ? "make_double" : "make_float") + n;
        d[std::string("make_mixed") + n] = std::string(doubleMixed ? "make_double" : "make_float") + n;
    }
    const char* functions[] = {"SQRT", "sqrt", "RSQRT", "rsqrt", "RECIP", "1.0/", "EXP",  "exp",  "LOG",  "log",
                               "POW",  "pow",  "COS",   "cos",   "SIN",   "sin",  "TAN",  "tan",  "ACOS", "acos",
                               "ASIN", "asin", "ATAN",  "atan",  "ERF",   "erf",  "ERFC", "erfc", "FMA",  "fma",
                               "FABS", "fabs"};
    for (size_t i = 0; i < sizeof(functions) / sizeof(functions[0]); i += 2) {
        std::string name = functions[i + 1];
        d[functions[i]] = p.useDouble ? name : (name == "1.0/" ? "1.0f/" : name + "f");
    }
    d["APPLY_PERIODIC_TO_DELTA(delta)"] = "{"
                                          "delta.x -= floor(delta.x*invPeriodicBoxSize.x+0.5f)*periodicBoxSize.x; \\\n"
                                          "delta.y -= floor(delta.y*invPeriodicBoxSize.y+0.5f)*periodicBoxSize.y; \\\n"
                                          "delta.z -= floor(delta.z*invPeriodicBoxSize.z+0.5f)*periodicBoxSize.z;}";
    d["APPLY_PERIODIC_TO_POS(pos)"] = "{"
                                      "pos.x -= floor(pos.x*invPeriodicBoxSize.x)*periodicBoxSize.x; \\\n"
                                      "pos.y -= floor(pos.y*invPeriodicBoxSize.y)*periodicBoxSize.y; \\\n"
                                      "pos.z -= floor(pos.z*invPeriodicBoxSize.z)*periodicBoxSize.z;}";
    d["APPLY_PERIODIC_TO_POS_WITH_CENTER(pos, center)"] =
        "{"
        "pos.x -= floor((pos.x-center.x)*invPeriodicBoxSize.x+0.5f)*periodicBoxSize.x; \\\n"
        "pos.y -= floor((pos.y-center.y)*invPeriodicBoxSize.y+0.5f)*periodicBoxSize.y; \\\n"
        "pos.z -= floor((pos.z-center.z)*invPeriodicBoxSize.z+0.5f)*periodicBoxSize.z;}";
    return d;
}

void writeDefines(std::ostream& out, const Defines& defines) {
    for (const auto& pair : defines) {
        out << "#define " << pair.first;
        if (!pair.second.empty())
            out << " " << pair.second;
        out << "\n";
    }
    if (!defines.empty())
        out << "\n";
}

/** The text createModule(vectorOps + source, defines) compiles, and the line where `source` starts. */
struct ModuleText {
    std::string text;
    int firstProgramLine;
};

ModuleText moduleText(const Precision& p, const std::string& source, const Defines& defines) {
    std::ostringstream src;
    src << "// Compilation Options: --use_fast_math\n\n";
    Defines context = contextDefines(p);
    for (const auto& pair : defines)
        context.erase(pair.first);  // the program's own define wins, as in createModule
    writeDefines(src, context);
    const char* real = p.useDouble ? "double" : "float";
    const char* mixed = (p.useDouble || p.useMixed) ? "double" : "float";
    src << "typedef " << real << " real;\ntypedef " << real << "2 real2;\ntypedef " << real << "3 real3;\ntypedef "
        << real << "4 real4;\n";
    src << "typedef " << mixed << " mixed;\ntypedef " << mixed << "2 mixed2;\ntypedef " << mixed << "3 mixed3;\ntypedef "
        << mixed << "4 mixed4;\n";
    src << "typedef unsigned int tileflags;\n";
    src << CudaKernelSources::common << "\n";
    writeDefines(src, defines);
    src << CudaKernelSources::vectorOps;
    const std::string prelude = src.str();
    return {prelude + source + "\n", 1 + static_cast<int>(std::count(prelude.begin(), prelude.end(), '\n'))};
}

/**
 * Compiles one program; prints NVRTC's diagnostics in the plugin's code in full and counts
 * those in OpenMM's prelude; writes the PTX and the text. False if NVRTC fails.
 */
bool compile(const std::string& name, const Precision& p, const ModuleText& module, const std::string& arch,
             const std::string& outputDir) {
    const std::string label = name + "-" + p.name;
    nvrtcProgram program;
    if (nvrtcCreateProgram(&program, module.text.c_str(), (label + ".cu").c_str(), 0, nullptr, nullptr) !=
        NVRTC_SUCCESS) {
        std::cout << label << ": nvrtcCreateProgram failed\n";
        return false;
    }
    const std::string archOption = "-arch=compute_" + arch;
    const char* options[] = {archOption.c_str(), "--use_fast_math"};
    const nvrtcResult result = nvrtcCompileProgram(program, 2, options);
    size_t logSize = 0;
    nvrtcGetProgramLogSize(program, &logSize);
    std::string log(logSize, '\0');
    nvrtcGetProgramLog(program, &log[0]);
    // A diagnostic starts "<label>.cu(<line>): warning|error ..." and runs to the next blank line.
    const std::regex start("^" + std::regex_replace(label, std::regex("[+]"), "\\+") + "\\.cu\\(([0-9]+)\\): (warning|error)");
    std::istringstream lines(log.c_str());
    std::string line, own;
    int preludeDiagnostics = 0, ownDiagnostics = 0;
    bool inOwn = false;
    std::smatch match;
    while (std::getline(lines, line)) {
        if (std::regex_search(line, match, start)) {
            inOwn = std::stoi(match[1]) >= module.firstProgramLine;
            (inOwn ? ownDiagnostics : preludeDiagnostics)++;
        }
        else if (line.empty())
            inOwn = false;
        if (inOwn)
            own += "    " + line + "\n";
    }
    std::cout << label << ": " << (result == NVRTC_SUCCESS ? "compiled" : nvrtcGetErrorString(result)) << ", "
              << ownDiagnostics << " diagnostics in the plugin's code (from line " << module.firstProgramLine << "), "
              << preludeDiagnostics << " in OpenMM's prelude\n"
              << own;
    if (result != NVRTC_SUCCESS && ownDiagnostics == 0)
        std::cout << log << "\n";
    if (result == NVRTC_SUCCESS) {
        size_t ptxSize = 0;
        nvrtcGetPTXSize(program, &ptxSize);
        std::vector<char> ptx(ptxSize);
        nvrtcGetPTX(program, ptx.data());
        std::ofstream(outputDir + "/" + label + ".ptx") << ptx.data();
    }
    std::ofstream(outputDir + "/" + label + ".cu") << module.text;  // what was compiled, for the log's line numbers
    std::ofstream(outputDir + "/" + label + ".log") << log.c_str();
    nvrtcDestroyProgram(&program);
    return result == NVRTC_SUCCESS;
}

} // namespace

int main(int argc, char** argv) {
    if (argc < 2 || argc > 3) {
        std::cerr << "usage: cuda_program_check OUTPUT_DIR [ARCH (default 90)]\n";
        return 2;
    }
    const std::string outputDir = argv[1], arch = argc > 2 ? argv[2] : "90";
    int major = 0, minor = 0;
    nvrtcVersion(&major, &minor);
    std::cout << "NVRTC " << major << "." << minor << ", compute_" << arch << "\n";
    // The programs the plugin compiles (CommonRigidBodyState::initialize): the step's, with
    // collisions.cc when the System has an AndersenThermostat, with thermostats.cc for the
    // thermostats, with drude.cc for the Drude integrators (and thermostats.cc for the
    // Nose-Hoover one).
    const std::vector<std::pair<std::string, std::string>> stepPrograms = {
        {"step", CommonRigidBodyState::programSource("")},
        {"step+collisions", CommonRigidBodyState::programSource(CommonMRattleKernelSources::collisions)},
        {"step+thermostats", CommonRigidBodyState::programSource(CommonMRattleKernelSources::thermostats)},
        {"step+drude", CommonRigidBodyState::programSource(CommonMRattleKernelSources::drude)},
        {"step+thermostats+drude", CommonRigidBodyState::programSource(CommonMRattleKernelSources::thermostats +
                                                                       CommonMRattleKernelSources::drude)}};
    const Precision precisions[] = {{"single", false, false}, {"mixed", false, true}, {"double", true, false}};
    int failed = 0;
    for (const Precision& p : precisions) {
        const Defines defines = CommonRigidBodyState::programDefines(p.useDouble, p.useMixed);
        for (const auto& program : stepPrograms)
            failed += !compile(program.first, p, moduleText(p, program.second, defines), arch, outputDir);
    }
    std::cout << (failed ? std::to_string(failed) + " program(s) failed\n" : "all programs compiled\n");
    return failed ? 1 : 0;
}
