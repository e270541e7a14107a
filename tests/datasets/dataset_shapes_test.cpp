// `generate` end to end through the real dataset loader (DatasetShapeLoader): the procedural
// corpus needs no data files.
#include "datasets/dataset_shapes.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "protocols/generate.hpp"
#include "protocols/pair_file.hpp"

namespace regbench {
namespace {

std::string FreshDir(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() / ("regbench_test_" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir.string();
}

GenerateRequest Request(const std::string& out, const std::string& dataset) {
    GenerateRequest r;
    r.dataset = dataset;
    r.split = "test";
    r.num_pairs = 4;
    r.seed = 9;
    r.out = out;
    return r;
}

TEST(DatasetShapeLoader, ProceduralDatasetThroughGenerate) {
    // Shapes load once, pairs come out with the protocol's point count (717 = 70% of 1024).
    const std::string dir = FreshDir("generate_procedural");
    GenerateToFile(Request(dir + "/p.h5", "procedural"), DatasetShapeLoader(DatasetOptions{}));
    const PairSet set = ReadPairFile(dir + "/p.h5");
    ASSERT_EQ(set.pairs.size(), 4u);
    EXPECT_EQ(set.pairs[0].source.rows(), 717);
    EXPECT_FALSE(set.pairs[0].shape.empty());
    std::filesystem::remove_all(dir);
}

TEST(DatasetShapeLoader, MissingDatasetPathFailsAndLeavesNoFile) {
    const std::string dir = FreshDir("generate_missing_dataset");
    const std::string out = dir + "/p.h5";
    try {
        GenerateToFile(Request(out, dir + "/no_such_dataset"),
                       DatasetShapeLoader(DatasetOptions{}));
        ADD_FAILURE() << "missing dataset path accepted";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("no_such_dataset"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(out));
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace regbench
