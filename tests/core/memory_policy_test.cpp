// RetainFreedMemory (core/memory_policy.hpp): after it, glibc serves a large block from the heap
// (not a private mmap) and keeps the heap when the block is freed, so the next allocation of
// that size reuses pages already faulted in. Checked with glibc's own accounting (mallinfo2):
// hblkhd is the bytes in mmapped blocks, arena the heap's size. Not built with a sanitizer,
// whose allocator replaces glibc's.
#include <gtest/gtest.h>

// GCC names a sanitizer build by macro, clang by __has_feature.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define REGBENCH_SANITIZER_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
#define REGBENCH_SANITIZER_ALLOCATOR 1
#endif
#endif

#if defined(__GLIBC__) && !defined(REGBENCH_SANITIZER_ALLOCATOR)
#include <malloc.h>

#include <cstdlib>
#include <cstring>

#include "core/memory_policy.hpp"

namespace regbench {
namespace {

TEST(MemoryPolicy, LargeBlocksComeFromTheHeapAndStayThereWhenFreed) {
    RetainFreedMemory();
    constexpr size_t kBytes = size_t{64} << 20;  // above glibc's largest mmap threshold (32 MiB)
    const size_t mmapped_before = mallinfo2().hblkhd;
    void* block = std::malloc(kBytes);
    ASSERT_NE(block, nullptr);
    std::memset(block, 1, kBytes);
    EXPECT_EQ(mallinfo2().hblkhd, mmapped_before) << "the block was mmapped";
    std::free(block);
    EXPECT_GE(mallinfo2().arena, kBytes) << "the heap was trimmed after the free";
}

}  // namespace
}  // namespace regbench
#endif
