#pragma once
// A small pair file of synthetic pairs (tests/testing/synthetic.hpp) for the tests that run
// the runner on one. Needs regbench_protocols (WritePairFile).
#include <functional>
#include <string>

#include "protocols/pair_file.hpp"
#include "tests/testing/synthetic.hpp"

namespace regbench::testing {

/// Writes `count` SyntheticPairs of `points` points to `path`: pair k has shape seed
/// first_seed + k and ground truth motion(k); the provenance is dataset "synthetic", protocol
/// "test" and seed `provenance_seed`.
inline void WriteSyntheticPairFile(const std::string& path,
                                   int count,
                                   Eigen::Index points,
                                   std::uint64_t first_seed,
                                   int provenance_seed,
                                   const std::function<Transform(int k)>& motion) {
    PairSet set;
    set.provenance = {{"dataset", "synthetic"}, {"protocol", "test"}, {"seed", provenance_seed}};
    for (int k = 0; k < count; ++k) {
        set.pairs.push_back(
            SyntheticPair(points, first_seed + static_cast<std::uint64_t>(k), motion(k)));
    }
    WritePairFile(path, set);
}

}  // namespace regbench::testing
