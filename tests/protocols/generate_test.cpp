#include "protocols/generate.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "protocols/pair_file.hpp"
#include "protocols/pair_summary.hpp"
#include "tests/protocols/test_shapes.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

/// Loader over the in-test shapes; counts calls so tests can prove no work was done.
struct CountingLoader {
    int* calls;
    std::vector<ShapeSource> operator()(const std::string& dataset, const std::string&) const {
        ++*calls;
        if (dataset != "test") throw std::runtime_error("dataset '" + dataset + "': not found");
        return test::TestShapes();
    }
};

GenerateRequest Request(const std::string& out) {
    GenerateRequest r;
    r.dataset = "test";
    r.num_pairs = 4;
    r.seed = 9;
    r.out = out;
    r.extra_provenance = {{"regbench_version", "x"}};
    return r;
}

TEST(Generate, WritesOneFileWithProvenanceAndProgress) {
    const std::string dir = testing::FreshTempDir("generate_ok");
    int calls = 0;
    std::size_t last = 0;
    GenerateToFile(Request(dir + "/p.h5"), CountingLoader{&calls},
                   [&](std::size_t done, std::size_t) { last = done; });
    EXPECT_EQ(calls, 1);
    EXPECT_EQ(last, 4u);
    const PairSet set = ReadPairFile(dir + "/p.h5");
    EXPECT_EQ(set.pairs.size(), 4u);
    EXPECT_EQ(set.provenance.at("dataset"), "test");
    EXPECT_EQ(set.provenance.at("seed"), 9);
    EXPECT_EQ(set.provenance.at("protocol"), "partial");
    EXPECT_EQ(set.provenance.at("regbench_version"), "x");
    EXPECT_FALSE(std::filesystem::exists(dir + "/p.h5.tmp"));
    const PairSetSummary s = SummarizePairSet(set);
    EXPECT_EQ(s.min_source_points, 717);
    EXPECT_LE(s.max_rotation_deg, 45.0 * std::sqrt(3.0));
    EXPECT_GT(s.gt_ccd_mean, 0.0);  // independent samples: no exact correspondences
    EXPECT_LT(s.gt_ccd_mean, 0.2);
    std::filesystem::remove_all(dir);
}

TEST(Generate, BadRequestsFailBeforeWorkAndLeaveNoFile) {
    const std::string dir = testing::FreshTempDir("generate_bad");
    const std::string out = dir + "/p.h5";
    int calls = 0;
    const auto fails = [&](GenerateRequest r, const std::string& needle) {
        try {
            GenerateToFile(r, CountingLoader{&calls});
            ADD_FAILURE() << "no error, expected " << needle;
        } catch (const std::exception& e) {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
        EXPECT_FALSE(std::filesystem::exists(out));
        EXPECT_FALSE(std::filesystem::exists(out + ".tmp"));
    };
    GenerateRequest r = Request(out);
    r.options.keep = 1.2;
    fails(r, "keep");
    r = Request(out);
    r.options.points = 2;
    fails(r, "points");
    r = Request(out);
    r.num_pairs = 0;
    fails(r, "pairs");
    r = Request(dir + "/no/such/dir/p.h5");
    fails(r, "does not exist");
    EXPECT_EQ(calls, 0);  // none of the above reached the loader
    r = Request(out);
    r.dataset = "missing";
    fails(r, "dataset 'missing'");
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace regbench
