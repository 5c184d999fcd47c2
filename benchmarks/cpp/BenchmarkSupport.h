#ifndef MRATTLE_BENCHMARK_SUPPORT_H_
#define MRATTLE_BENCHMARK_SUPPORT_H_

// What the timing programs (step_cost, device_speed) share: their comma-separated option
// lists, their two CSV outputs, the wall clock, and the median they report.

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <sstream>
#include <string>
#include <vector>

namespace MRattleBenchmark {

using Clock = std::chrono::steady_clock;

/** Wall-clock seconds since a time point. */
inline double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

/** The median (the mean of the middle two for an even count); values must not be empty. */
inline double median(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    size_t n = values.size();
    return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/** The items of a comma-separated option value, empty ones dropped. */
inline std::vector<std::string> split(const std::string& text) {
    std::vector<std::string> parts;
    std::stringstream stream(text);
    std::string part;
    while (std::getline(stream, part, ','))
        if (!part.empty())
            parts.push_back(part);
    return parts;
}

/** A comma-separated list of integers (std::stoi throws on one that is not). */
inline std::vector<int> splitInts(const std::string& text) {
    std::vector<int> values;
    for (const std::string& part : split(text))
        values.push_back(std::stoi(part));
    return values;
}

/** The two CSV outputs: timings to --out (default stdout), targets to --ratios (default stderr). */
struct CsvOutputs {
    CsvOutputs(const std::string& outPath, const std::string& ratiosPath)
        : out(open(outPath, outFile, std::cout)), ratios(open(ratiosPath, ratioFile, std::cerr)) {}
    std::ofstream outFile, ratioFile;  // declared before the references bound to them
    std::ostream& out;
    std::ostream& ratios;

private:
    static std::ostream& open(const std::string& path, std::ofstream& file, std::ostream& fallback) {
        if (path.empty())
            return fallback;
        file.open(path);
        if (!file)
            throw std::runtime_error("cannot write " + path);
        return file;
    }
};

} // namespace MRattleBenchmark

#endif
