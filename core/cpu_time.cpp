#include "core/cpu_time.hpp"

#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>

namespace regbench {

double ThreadCpuSeconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double ProcessCpuSeconds() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const auto seconds = [](const timeval& tv) {
        return static_cast<double>(tv.tv_sec) + 1e-6 * static_cast<double>(tv.tv_usec);
    };
    return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

CpuStopwatch::CpuStopwatch(int threads)
    : use_process_(threads > 1), start_(use_process_ ? ProcessCpuSeconds() : ThreadCpuSeconds()) {}

double CpuStopwatch::Elapsed() const {
    return (use_process_ ? ProcessCpuSeconds() : ThreadCpuSeconds()) - start_;
}

int MachineLoad::FreeCores() const {
    if (load1 < 0.0) return cores;
    return std::max(0, static_cast<int>(std::floor(cores - load1)));
}

MachineLoad ReadMachineLoad() {
    MachineLoad load;
    load.cores = static_cast<int>(std::max(1L, sysconf(_SC_NPROCESSORS_ONLN)));
    std::ifstream in("/proc/loadavg");
    double a = 0, b = 0, c = 0;
    if (in >> a >> b >> c) {
        load.load1 = a;
        load.load5 = b;
        load.load15 = c;
    }
    return load;
}

std::string CpuModel() {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("model name", 0) == 0) {
            const auto colon = line.find(':');
            if (colon != std::string::npos) {
                std::string v = line.substr(colon + 1);
                v.erase(0, v.find_first_not_of(' '));
                return v;
            }
        }
    }
    return "unknown CPU";
}

}  // namespace regbench
