#pragma once
// A small pair file of synthetic pairs (tests/testing/synthetic.hpp) for the tests that run
// the runner on one, and a fixture that writes one per test. Needs regbench_protocols
// (WritePairFile).
#include <functional>
#include <string>
#include <utility>

#include "protocols/pair_file.hpp"
#include "tests/testing/synthetic.hpp"
#include "tests/testing/temp_dir_test.hpp"

namespace regbench::testing {

/// Writes `count` SyntheticPairs of `points` points to `path`: pair k has shape seed
/// first_seed + k and ground truth motion(k); the provenance is dataset "synthetic", protocol
/// "test" and seed `provenance_seed`.
inline void WriteSyntheticPairFile(const std::string& path, int count, Eigen::Index points,
                                   std::uint64_t first_seed, int provenance_seed,
                                   const std::function<Transform(int k)>& motion) {
    PairSet set;
    set.provenance = {{"dataset", "synthetic"}, {"protocol", "test"}, {"seed", provenance_seed}};
    for (int k = 0; k < count; ++k) {
        set.pairs.push_back(
            SyntheticPair(points, first_seed + static_cast<std::uint64_t>(k), motion(k)));
    }
    WritePairFile(path, set);
}

/// Motion of pair k: a turn of 5k degrees about z and a shift of 0.01k along x.
inline Transform TurnAboutZ(int k) {
    return MakeTransform(RotationZyxProductDeg(5.0 * k, 0, 0), {0.01 * k, 0, 0});
}

/// A TempDirTest whose SetUp writes WriteSyntheticPairFile(pairs_, ...) with the arguments
/// the derived fixture's constructor gives, pairs_ being Path("pairs.h5").
class PairFileTest : public TempDirTest {
protected:
    PairFileTest(int count, Eigen::Index points, std::uint64_t first_seed, int provenance_seed,
                 std::function<Transform(int k)> motion = TurnAboutZ)
        : count_(count),
          points_(points),
          first_seed_(first_seed),
          provenance_seed_(provenance_seed),
          motion_(std::move(motion)) {}

    void SetUp() override {
        TempDirTest::SetUp();
        pairs_ = Path("pairs.h5");
        WriteSyntheticPairFile(pairs_, count_, points_, first_seed_, provenance_seed_, motion_);
    }

    std::string pairs_;

private:
    int count_;
    Eigen::Index points_;
    std::uint64_t first_seed_;
    int provenance_seed_;
    std::function<Transform(int k)> motion_;
};

}  // namespace regbench::testing
