#pragma once
// One place that sets the OpenMP thread count the registration methods use.
#include <omp.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace regbench {

/// The most OpenMP threads one call may ask for: far above any machine regbench runs on, and far
/// below the count at which libgomp cannot allocate its team and kills the process (10^9 threads
/// ended the Python interpreter; issue 44).
inline constexpr int kMaxThreads = 1024;

/// Sets the OpenMP thread count for parallel regions started by the calling thread.
///
/// Also sets the OMP_NUM_THREADS environment variable, because Open3D 0.16's
/// utility::EstimateMaxThreads() (used as num_threads(...) by EstimateNormals and
/// ComputeFPFHFeature) returns the hardware thread count, ignoring omp_set_num_threads(),
/// whenever OMP_NUM_THREADS is absent; with the variable present it returns
/// omp_get_max_threads(). (Open3D's RegistrationICP and PCL 1.13's GICP/NDT need no help: the
/// former follows omp_set_num_threads(), the latter are single-threaded.)
///
/// @note omp_set_num_threads() is per thread: a worker std::thread starts from the process
/// default (OMP_NUM_THREADS at start-up, else all cores) and must call this itself.
/// setenv is not thread-safe: call this while no other thread runs a method.
inline void SetOmpThreads(int threads) {
    if (threads < 1 || threads > kMaxThreads) {
        throw std::invalid_argument("threads must be in [1, " + std::to_string(kMaxThreads) +
                                    "], got " + std::to_string(threads));
    }
    setenv("OMP_NUM_THREADS", std::to_string(threads).c_str(), /*overwrite=*/1);
    omp_set_num_threads(threads);
}

}  // namespace regbench
