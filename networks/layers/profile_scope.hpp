#pragma once
// Named stages for LibTorch's profiler (bench/networks/profile_tool.cpp): a scope shows up as one
// row with its inclusive time, so a forward breaks down by stage (dgcnn, attention, GMM fit...)
// as well as by operator. When no profiler is active a scope costs one thread-local check.
#include <ATen/record_function.h>

#define REGBENCH_PROFILE_SCOPE(name) RECORD_USER_SCOPE(name)
