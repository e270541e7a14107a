#include "protocols/pair_hash.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "protocols/pair_file.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

PairSet OnePointPair() {
    Pair p;
    p.source = PointCloud(1, 3);
    p.source << 1, 2, 3;
    p.target = PointCloud(1, 3);
    p.target << 4, 5, 6;
    p.source_overlap = Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1>::Constant(1, 1);
    p.target_overlap = Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1>::Constant(1, 0);
    p.source_overlap_ratio = 1.0;
    p.shape = "s";
    p.category = "c";
    PairSet set;
    set.provenance = {{"seed", 1}};
    set.pairs.push_back(p);
    return set;
}

TEST(PairHash, MatchesAnIndependentFnv1aOfTheDocumentedBytes) {
    // /usr/bin/python3: FNV-1a 64 over struct.pack('<Q', 1) (pairs), then per cloud
    // '<Q' count + '<d' x, y, z; T_gt as 16 '<d' row-major; labels '<Q' count + bytes;
    // shape and category '<Q' length + bytes  ->  fnv1a64:69c6154a277e2620
    EXPECT_EQ(PairSetContentHash(OnePointPair()), "fnv1a64:69c6154a277e2620");
}

TEST(PairHash, SurvivesAFileRoundTripAndSeesOneChangedCoordinate) {
    const PairSet set = OnePointPair();
    const auto path = regbench::testing::TempPath("pair_hash.h5");
    WritePairFile(path.string(), set);
    EXPECT_EQ(PairSetContentHash(ReadPairFile(path.string())), PairSetContentHash(set));
    std::filesystem::remove(path);
    PairSet moved = set;
    moved.pairs[0].target(0, 2) = std::nextafter(6.0, 7.0);
    EXPECT_NE(PairSetContentHash(moved), PairSetContentHash(set));
    PairSet other_provenance = set;
    other_provenance.provenance["note"] = "x";  // provenance is not part of the content
    EXPECT_EQ(PairSetContentHash(other_provenance), PairSetContentHash(set));
}

}  // namespace
}  // namespace regbench
