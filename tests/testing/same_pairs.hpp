#pragma once
// Pair-by-pair comparison of two pair sets (protocols/pair.hpp), for the tests that write pairs
// to a file format and read them back.
#include <gtest/gtest.h>

#include <cstddef>
#include <string>

#include "protocols/pair.hpp"

namespace regbench::testing {

/// Expects `actual` to hold as many pairs as `expected`, each with the same points, ground truth
/// and overlap labels, bit for bit; a failure names the pair's index. The names and ratios are
/// left to the caller: not every format stores them.
inline void ExpectSamePairs(const PairSet& actual, const PairSet& expected) {
    ASSERT_EQ(actual.pairs.size(), expected.pairs.size());
    for (std::size_t k = 0; k < expected.pairs.size(); ++k) {
        SCOPED_TRACE("pair " + std::to_string(k));
        const Pair& a = actual.pairs[k];
        const Pair& e = expected.pairs[k];
        EXPECT_EQ(a.source, e.source);
        EXPECT_EQ(a.target, e.target);
        EXPECT_EQ(a.T_gt, e.T_gt);
        EXPECT_EQ(a.source_overlap, e.source_overlap);
        EXPECT_EQ(a.target_overlap, e.target_overlap);
    }
}

}  // namespace regbench::testing
