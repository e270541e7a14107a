#pragma once
// The fixture of the networks' tests: LibTorch on one thread (its intra-op pool would
// otherwise take every core, and the tests' float tolerances were set single-threaded).
#include <gtest/gtest.h>
#include <torch/torch.h>

namespace regbench::networks {

class OneThreadTest : public ::testing::Test {
protected:
    void SetUp() override { torch::set_num_threads(1); }
};

}  // namespace regbench::networks
