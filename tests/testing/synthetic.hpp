#pragma once
// Small synthetic benchmark pairs (protocols/pair.hpp) for tests that must not depend on the
// mesh corpus. For shapes alone include tests/testing/shapes.hpp (core/ only).
#include "protocols/pair.hpp"
#include "tests/testing/shapes.hpp"

namespace regbench::testing {

/// A pair whose target is T_gt applied to an independent sample of the same surface.
inline Pair SyntheticPair(Eigen::Index n, std::uint64_t seed, const Transform& T_gt) {
    Pair p;
    p.source = BumpyEllipsoid(n, seed);
    p.target = Apply(T_gt, BumpyEllipsoid(n, seed + 1000));
    p.T_gt = T_gt;
    p.source_overlap.setOnes(n);
    p.target_overlap.setOnes(n);
    p.source_overlap_ratio = p.target_overlap_ratio = 1.0;
    p.shape = "bumpy_ellipsoid";
    p.category = "synthetic";
    return p;
}

}  // namespace regbench::testing
