#pragma once
// The multiply-accumulate floor of a learned network on this machine (docs/performance.md,
// section 6): its MAC count (networks/cost.hpp) over the single-thread fp32 GEMM rate measured in
// the same process, and the BLAS that rate comes from.
#include <string>

namespace regbench::networks {

/// The single-thread fp32 GEMM rate of this process.
struct GemmRate {
    double macs_per_second = 0.0;  ///< multiply-accumulates per CPU second of the calling thread
    double cpu_seconds = 0.0;      ///< CPU time the measurement took
    int repetitions = 0;           ///< GEMMs timed
};

/// Times a [717, 512] x [512, 512] fp32 torch::mm_out (the shape bench/ogmm's
/// BM_OgmmForward uses) with one torch thread and one BLAS thread, by the calling thread's CPU
/// clock, until at least `min_cpu_seconds` have passed (after two untimed warm-up products).
/// The torch and BLAS thread counts are restored afterwards.
GemmRate MeasureGemmRate(double min_cpu_seconds = 0.2);

/// MeasureGemmRate() of the first call in this process, cached (thread-safe). A process that
/// forks after the first call hands the value to its children, so a run's isolated calls
/// measure nothing.
const GemmRate& ProcessGemmRate();

/// Sets the thread count of the BLAS under LibTorch. torch::set_num_threads does not reach an
/// OpenBLAS built with pthreads (Debian's default), which starts one thread per core unless
/// OPENBLAS_NUM_THREADS or OMP_NUM_THREADS was set before the process started. No effect when
/// the BLAS is not OpenBLAS.
void SetBlasThreads(int threads);

/// The BLAS LibTorch's GEMMs run on, e.g. "OpenBLAS 0.3.21 NO_LAPACKE DYNAMIC_ARCH NO_AFFINITY
/// Cooperlake MAX_THREADS=64 (pthreads)"; "unknown (LibTorch BLAS_INFO=...)" when it is not
/// OpenBLAS.
std::string BlasDescription();

/// The LibTorch version this binary was built with (TORCH_VERSION, e.g. "1.13.0").
std::string LibTorchVersion();

}  // namespace regbench::networks
