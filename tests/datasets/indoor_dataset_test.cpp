#include "datasets/indoor_dataset.hpp"

#include <gtest/gtest.h>

#include "datasets/dataset_shapes.hpp"

namespace regbench {
namespace {

TEST(IndoorSimDataset, SplitsAreDisjointScenesAndDeterministic) {
    DatasetOptions options;
    options.seed = 11;
    const std::vector<ShapeSource> val = LoadIndoorSimShapes("val", options);
    ASSERT_EQ(val.size(), 6u);
    const std::vector<ShapeSource> again = DatasetShapeLoader(options)("indoor-sim", "val");
    ASSERT_EQ(again.size(), 6u);
    for (std::size_t i = 0; i < val.size(); ++i) {
        EXPECT_EQ(val[i].name(), "room_" + std::to_string(24 + i));
        EXPECT_EQ(val[i].category(), "indoor_sim");
        EXPECT_FALSE(val[i].is_mesh());
        EXPECT_GT(val[i].size(), 2048) << "a scan must hold enough points to resample";
        EXPECT_EQ(val[i].size(), again[i].size());
        std::mt19937_64 a(5), b(5);
        EXPECT_EQ(val[i].Sample(100, a), again[i].Sample(100, b));
    }
    // Scans are in metres in the camera frame: depth (z) within the sensor's range.
    std::mt19937_64 rng(1);
    const PointCloud p = val[0].Sample(1000, rng);
    EXPECT_GT(p.col(2).minCoeff(), 0.4);
    EXPECT_LT(p.col(2).maxCoeff(), 4.1);
    EXPECT_THROW(LoadIndoorSimShapes("nosuch", options), std::invalid_argument);
}

}  // namespace
}  // namespace regbench
