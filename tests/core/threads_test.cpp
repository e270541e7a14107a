#include "core/threads.hpp"

#include <gtest/gtest.h>

namespace regbench {
namespace {

TEST(SetOmpThreads, SetsOpenMpAndEnvironment) {
    const int previous = omp_get_max_threads();
    SetOmpThreads(1);
    EXPECT_EQ(omp_get_max_threads(), 1);
    ASSERT_NE(std::getenv("OMP_NUM_THREADS"), nullptr);
    EXPECT_STREQ(std::getenv("OMP_NUM_THREADS"), "1");
    int seen = 0;
#pragma omp parallel
    {
#pragma omp single
        seen = omp_get_num_threads();
    }
    EXPECT_EQ(seen, 1);
    SetOmpThreads(previous);
    EXPECT_EQ(omp_get_max_threads(), previous);
}

TEST(SetOmpThreads, RejectsNonPositive) { EXPECT_THROW(SetOmpThreads(0), std::invalid_argument); }

}  // namespace
}  // namespace regbench
