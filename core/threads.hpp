#pragma once
// One place that sets the OpenMP thread count the registration methods use.
#include <omp.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace regbench {

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
    if (threads < 1) {
        throw std::invalid_argument("threads must be >= 1, got " + std::to_string(threads));
    }
    setenv("OMP_NUM_THREADS", std::to_string(threads).c_str(), /*overwrite=*/1);
    omp_set_num_threads(threads);
}

}  // namespace regbench
