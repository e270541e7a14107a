#include "protocols/pair_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/testing/files.hpp"
#include "tests/testing/same_pairs.hpp"
#include "tests/testing/synthetic.hpp"

namespace regbench {
namespace {

std::string TempPath(const std::string& name) { return regbench::testing::TempPath(name).string(); }

PairSet TwoPairs() {
    PairSet set;
    set.provenance = {{"protocol", "test"}, {"seed", 5}};
    set.pairs.push_back(testing::SyntheticPair(
        20, 1, MakeTransform(RotationFromEulerZyxDeg(10, 0, 0), {0.1, 0, 0})));
    set.pairs.push_back(testing::SyntheticPair(30, 2, Transform::Identity()));
    set.pairs[1].target_overlap[3] = 0;
    set.pairs[1].target_overlap_ratio = 29.0 / 30.0;
    return set;
}

TEST(PairFile, RoundTripsEveryField) {
    const std::string path = TempPath("roundtrip.h5");
    const PairSet set = TwoPairs();
    WritePairFile(path, set);
    EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
    const PairSet back = ReadPairFile(path);
    EXPECT_EQ(back.provenance, set.provenance);
    ASSERT_EQ(back.pairs.size(), 2u);
    EXPECT_EQ(CountPairs(path), 2u);
    testing::ExpectSamePairs(back, set);
    for (std::size_t k = 0; k < 2; ++k) {
        SCOPED_TRACE("pair " + std::to_string(k));
        EXPECT_EQ(back.pairs[k].shape, set.pairs[k].shape);
        EXPECT_EQ(back.pairs[k].category, set.pairs[k].category);
        EXPECT_DOUBLE_EQ(back.pairs[k].target_overlap_ratio, set.pairs[k].target_overlap_ratio);
    }
    std::filesystem::remove(path);
}

TEST(PairFile, SameContentGivesIdenticalBytes) {
    const std::string a = TempPath("bytes_a.h5");
    const std::string b = TempPath("bytes_b.h5");
    WritePairFile(a, TwoPairs());
    WritePairFile(b, TwoPairs());
    std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
    const std::string sa((std::istreambuf_iterator<char>(fa)), {});
    const std::string sb((std::istreambuf_iterator<char>(fb)), {});
    EXPECT_EQ(sa, sb);
    std::filesystem::remove(a);
    std::filesystem::remove(b);
}

TEST(PairFile, RejectsMissingTruncatedAndForeignFiles) {
    EXPECT_THROW(
        {
            try {
                ReadPairFile("/nonexistent/pairs.h5");
            } catch (const std::runtime_error& e) {
                EXPECT_NE(std::string(e.what()).find("/nonexistent/pairs.h5"), std::string::npos);
                throw;
            }
        },
        std::runtime_error);
    const std::string path = TempPath("truncated.h5");
    WritePairFile(path, TwoPairs());
    const auto size = std::filesystem::file_size(path);
    std::filesystem::resize_file(path, size / 2);
    try {
        ReadPairFile(path);
        FAIL() << "truncated file was accepted";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    std::ofstream(path, std::ios::trunc) << "not hdf5 at all";
    EXPECT_THROW(ReadPairFile(path), std::runtime_error);
    std::filesystem::remove(path);
}

TEST(PairFile, RejectsLabelsThatDoNotMatchPoints) {
    PairSet set = TwoPairs();
    set.pairs[0].source_overlap.resize(3);
    const std::string path = TempPath("badlabels.h5");
    EXPECT_THROW(WritePairFile(path, set), std::runtime_error);
    EXPECT_FALSE(std::filesystem::exists(path));
    EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

}  // namespace
}  // namespace regbench
