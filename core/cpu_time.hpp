#pragma once
// CPU-time clocks and machine load, for timings that stay honest on a shared machine.
//
// Wall time (steady_clock) doubles when another process holds the core a method runs on; the
// CPU time the method's own threads consumed does not. RegistrationMethod::Align records both.
#include <string>

namespace regbench {

/// CPU seconds consumed so far by the calling thread (CLOCK_THREAD_CPUTIME_ID).
double ThreadCpuSeconds();

/// CPU seconds (user + system) consumed so far by every thread of this process
/// (getrusage(RUSAGE_SELF)). Includes OpenMP worker threads, and also any other thread of the
/// process that happens to run concurrently (e.g. another `--jobs` worker).
double ProcessCpuSeconds();

/// Measures the CPU time of one call. With `threads` <= 1 it reads the calling thread's clock
/// (exact, whatever else the process does); with `threads` > 1 it reads the process clock, so
/// the OpenMP workers' time counts too (exact when the call is the only thing the process
/// runs, e.g. in the runner's isolated child; an over-estimate while other jobs run in the
/// same process).
class CpuStopwatch {
public:
    explicit CpuStopwatch(int threads);
    /// CPU seconds since construction, by the clock chosen there.
    double Elapsed() const;
    /// "thread" or "process": which clock Elapsed() reads.
    const char* Scope() const { return use_process_ ? "process" : "thread"; }

private:
    bool use_process_;
    double start_;
};

/// The machine's load right now: /proc/loadavg and the online core count.
struct MachineLoad {
    double load1 = -1.0, load5 = -1.0, load15 = -1.0;  ///< -1 when /proc/loadavg is unreadable
    int cores = 1;                                     ///< online logical cores
    /// Cores not busy on average over the last minute: max(0, cores - load1) (rounded down;
    /// = cores when the load is unknown).
    int FreeCores() const;
};
MachineLoad ReadMachineLoad();

/// The CPU model from /proc/cpuinfo's first "model name" ("unknown CPU" when unreadable):
/// timing provenance of result rows, Tab. 6 and the benchmarks.
std::string CpuModel();

}  // namespace regbench
