// regbench_bench main: records the machine context with every run.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdlib>
#include <string>
#include <thread>

#include "core/cpu_time.hpp"
#include "core/memory_policy.hpp"
#include "core/version.hpp"

int main(int argc, char** argv) {
    // As `regbench` runs: freed memory kept for reuse (core/memory_policy.hpp); REGBENCH_MALLOC=
    // default keeps glibc's (for A/B runs).
    const char* malloc_mode = std::getenv("REGBENCH_MALLOC");
    if (malloc_mode == nullptr || std::string(malloc_mode) != "default") {
        regbench::RetainFreedMemory();
    }
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::AddCustomContext("cpu_model", regbench::CpuModel());
    benchmark::AddCustomContext("compiler", __VERSION__);
    benchmark::AddCustomContext("git_sha", regbench::RegbenchGitSha());
    benchmark::AddCustomContext("hardware_threads",
                                std::to_string(std::thread::hardware_concurrency()));
    benchmark::AddCustomContext("omp_max_threads", std::to_string(omp_get_max_threads()));
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
