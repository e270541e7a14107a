#include "networks/gemm_floor.hpp"

#include <gtest/gtest.h>
#include <torch/torch.h>

namespace regbench::networks {
namespace {

TEST(GemmFloor, MeasuresWithOneThreadAndRestoresTheThreadCounts) {
    torch::set_num_threads(2);
    const GemmRate r = MeasureGemmRate(0.01);
    EXPECT_GE(r.repetitions, 3);
    EXPECT_GT(r.cpu_seconds, 0.0);
    EXPECT_GT(r.macs_per_second, 0.0);
    EXPECT_EQ(torch::get_num_threads(), 2);
    torch::set_num_threads(1);
}

TEST(GemmFloor, TheProcessRateIsMeasuredOnce) {
    const GemmRate& a = ProcessGemmRate();
    const GemmRate& b = ProcessGemmRate();
    EXPECT_EQ(&a, &b);
    EXPECT_GT(a.macs_per_second, 0.0);
}

TEST(GemmFloor, NamesTheBlas) {
    // Debian's LibTorch runs on OpenBLAS (libblas.so.3); another BLAS is named as unknown.
    const std::string blas = BlasDescription();
    EXPECT_TRUE(blas.rfind("OpenBLAS", 0) == 0 || blas.rfind("unknown (LibTorch", 0) == 0) << blas;
}

}  // namespace
}  // namespace regbench::networks
