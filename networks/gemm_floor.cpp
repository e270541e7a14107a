#include "networks/gemm_floor.hpp"

#include <ATen/Version.h>
#include <dlfcn.h>
#include <torch/torch.h>
#include <torch/version.h>

#include <algorithm>

#include "core/cpu_time.hpp"

namespace regbench::networks {
namespace {

constexpr std::int64_t kRows = 717, kInner = 512, kCols = 512;

/// An OpenBLAS entry point of the process (LibTorch links the system BLAS; on Debian that is
/// OpenBLAS through libblas.so.3), or null when the BLAS is another one.
template <class F>
F OpenBlas(const char* name) {
    return reinterpret_cast<F>(dlsym(RTLD_DEFAULT, name));
}

int BlasThreads() {
    const auto get = OpenBlas<int (*)()>("openblas_get_num_threads");
    return get != nullptr ? get() : 1;
}

}  // namespace

void SetBlasThreads(int threads) {
    const auto set = OpenBlas<void (*)(int)>("openblas_set_num_threads");
    if (set != nullptr) set(std::max(1, threads));
}

GemmRate MeasureGemmRate(double min_cpu_seconds) {
    const int torch_threads = torch::get_num_threads();
    const int blas_threads = BlasThreads();
    torch::set_num_threads(1);
    SetBlasThreads(1);
    torch::NoGradGuard no_grad;
    // A generator of its own: the measurement leaves torch's global RNG alone.
    const at::Generator generator = at::detail::createCPUGenerator(1);
    const torch::Tensor a = torch::rand({kRows, kInner}, generator);
    const torch::Tensor b = torch::rand({kInner, kCols}, generator);
    torch::Tensor c = torch::empty({kRows, kCols});
    for (int i = 0; i < 2; ++i) torch::mm_out(c, a, b);  // warm-up: pages, packing buffers
    GemmRate r;
    const double t0 = ThreadCpuSeconds();
    do {
        torch::mm_out(c, a, b);
        ++r.repetitions;
        r.cpu_seconds = ThreadCpuSeconds() - t0;
    } while (r.cpu_seconds < min_cpu_seconds || r.repetitions < 3);
    r.macs_per_second = static_cast<double>(r.repetitions * kRows * kInner * kCols) / r.cpu_seconds;
    torch::set_num_threads(torch_threads);
    SetBlasThreads(blas_threads);
    return r;
}

const GemmRate& ProcessGemmRate() {
    static const GemmRate kRate = MeasureGemmRate();
    return kRate;
}

std::string BlasDescription() {
    const auto config = OpenBlas<char* (*)()>("openblas_get_config");
    if (config == nullptr) {
        const std::string all = at::show_config();
        const auto at = all.find("BLAS_INFO=");
        const std::string info =
            at == std::string::npos ? "?" : all.substr(at, all.find(',', at) - at);
        return "unknown (LibTorch " + info + ")";
    }
    const auto parallel = OpenBlas<int (*)()>("openblas_get_parallel");
    const int p = parallel != nullptr ? parallel() : -1;
    return std::string(config()) + (p == 0   ? " (sequential)"
                                    : p == 1 ? " (pthreads)"
                                    : p == 2 ? " (OpenMP)"
                                             : "");
}

std::string LibTorchVersion() { return TORCH_VERSION; }

}  // namespace regbench::networks
