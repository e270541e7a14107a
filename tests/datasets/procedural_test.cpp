#include "datasets/procedural.hpp"

#include <gtest/gtest.h>

#include <map>
#include <utility>

namespace regbench {
namespace {

/// Number of undirected edges not shared by exactly two triangles (0 for a closed surface).
int OpenOrNonManifoldEdges(const Mesh& mesh) {
    std::map<std::pair<int, int>, int> uses;
    for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
        for (int k = 0; k < 3; ++k) {
            const int a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 3);
            ++uses[{std::min(a, b), std::max(a, b)}];
        }
    }
    int bad = 0;
    for (const auto& [edge, count] : uses) bad += count != 2;
    return bad;
}

TEST(Procedural, EveryCategoryGivesClosedNonDegenerateMeshes) {
    const auto& categories = ProceduralCategories();
    ASSERT_EQ(categories.size(), 10u);
    EXPECT_TRUE(std::is_sorted(categories.begin(), categories.end()));
    for (int label = 0; label < static_cast<int>(categories.size()); ++label) {
        for (std::uint64_t index = 0; index < 3; ++index) {
            const Mesh mesh = MakeProceduralShape(label, 11, index);
            SCOPED_TRACE(categories[static_cast<std::size_t>(label)] + " #" +
                         std::to_string(index));
            ASSERT_GE(mesh.faces.rows(), 12);
            EXPECT_GE(mesh.faces.minCoeff(), 0);
            EXPECT_LT(mesh.faces.maxCoeff(), mesh.vertices.rows());
            EXPECT_TRUE(mesh.vertices.allFinite());
            EXPECT_GT(SurfaceArea(mesh), 0.1);
            EXPECT_LT(mesh.vertices.cwiseAbs().maxCoeff(), 2.5);
            EXPECT_EQ(OpenOrNonManifoldEdges(mesh), 0);
        }
    }
}

TEST(Procedural, DependsOnlyOnSeedCategoryAndIndex) {
    const Mesh a = MakeProceduralShape(6, 3, 4);
    EXPECT_EQ(a.vertices, MakeProceduralShape(6, 3, 4).vertices);
    EXPECT_NE(a.vertices, MakeProceduralShape(6, 3, 5).vertices);
    EXPECT_NE(a.vertices, MakeProceduralShape(6, 4, 4).vertices);
    EXPECT_THROW(MakeProceduralShape(10, 0, 0), std::invalid_argument);
    EXPECT_THROW(MakeProceduralShape(-1, 0, 0), std::invalid_argument);
}

}  // namespace
}  // namespace regbench
