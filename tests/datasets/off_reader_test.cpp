// ReadOff, and the mesh operations (protocols/mesh.hpp) on meshes it reads.
#include "datasets/off_reader.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>
#include <stdexcept>
#include <string>

#include "core/rng.hpp"
#include "tests/testing/expect_throw.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

constexpr double kTol = 1e-12;

std::string WriteFile(const std::string& name, const std::string& text) {
    const std::string path = ::testing::TempDir() + "regbench_mesh_test_" + name;
    std::ofstream(path) << text;
    return path;
}

using testing::ExpectThrowsWith;

// Unit square in z = 0 as one quad (fanned into two triangles) plus an apex triangle.
constexpr const char* kQuadOff =
    "OFF\n"
    "# a comment line\n"
    "5 2 0\n"
    "0 0 0\n"
    "1 0 0   # trailing comment\n"
    "1 1 0\n"
    "0 1 0\n"
    "\n"
    "0 0 1\n"
    "4 0 1 2 3\n"
    "3 0 1 4 255 0 0\n";  // face colour ignored

TEST(ReadOff, ReadsCommentsPolygonsAndIgnoresColours) {
    const Mesh mesh = ReadOff(WriteFile("quad.off", kQuadOff));
    ASSERT_EQ(mesh.vertices.rows(), 5);
    ASSERT_EQ(mesh.faces.rows(), 3);  // quad -> 2 triangles, + 1 triangle
    EXPECT_EQ(mesh.faces.row(0), Eigen::RowVector3i(0, 1, 2));
    EXPECT_EQ(mesh.faces.row(1), Eigen::RowVector3i(0, 2, 3));
    EXPECT_EQ(mesh.faces.row(2), Eigen::RowVector3i(0, 1, 4));
    EXPECT_EQ(mesh.vertices(4, 2), 1.0);
    // Unit square (1) + right triangle with legs 1 and 1 (0.5).
    EXPECT_NEAR(SurfaceArea(mesh), 1.5, kTol);
}

/// A one-triangle file in one of the header variants the reader accepts, and the mesh it holds.
struct HeaderVariant {
    const char* name;
    const char* text;
    decltype(Mesh::vertices) vertices;
    decltype(Mesh::faces) faces;
    double area;  ///< by hand from the vertices
};

TEST(ReadOff, AcceptsHeaderVariantsAndVertexExtras) {
    const auto triangle = [](double leg) {
        decltype(Mesh::vertices) v(3, 3);
        v << 0, 0, 0, leg, 0, 0, 0, leg, 0;
        return v;
    };
    const auto face = [](int a, int b, int c) {
        decltype(Mesh::faces) f(1, 3);
        f << a, b, c;
        return f;
    };
    const HeaderVariant variants[] = {
        // ModelNet40's malformed header: "OFF" and the counts run together on one line.
        // Right triangle with legs 2 and 2: area 2.
        {"modelnet.off", "OFF3 1 0\n0 0 0\n2 0 0\n0 2 0\n3 0 1 2\n", triangle(2), face(0, 1, 2),
         2.0},
        // COFF: RGBA after each vertex, ignored. Legs 1 and 1: area 0.5.
        {"c.off",
         "COFF\n3 1 0\n"
         "0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n"
         "3 0 1 2\n",
         triangle(1), face(0, 1, 2), 0.5},
        // NOFF with the counts on the header line: a normal after each vertex, ignored; the
        // face's vertex order is kept.
        {"n.off",
         "NOFF 3 1 0\n"
         "0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n"
         "3 2 1 0\n",
         triangle(1), face(2, 1, 0), 0.5},
    };
    for (const HeaderVariant& v : variants) {
        SCOPED_TRACE(v.name);
        const Mesh mesh = ReadOff(WriteFile(v.name, v.text));
        ASSERT_EQ(mesh.vertices.rows(), v.vertices.rows());
        ASSERT_EQ(mesh.faces.rows(), v.faces.rows());
        EXPECT_EQ(mesh.vertices, v.vertices);
        EXPECT_EQ(mesh.faces, v.faces);
        EXPECT_NEAR(SurfaceArea(mesh), v.area, kTol);
    }
}

TEST(ReadOff, RejectsTruncatedFileNamingPath) {
    const std::string path = WriteFile("truncated.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n");
    ExpectThrowsWith([&] { ReadOff(path); }, path);
    const std::string no_faces =
        WriteFile("noface.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1 2\n");
    ExpectThrowsWith([&] { ReadOff(no_faces); }, no_faces);
}

TEST(ReadOff, RejectsCorruptFilesNamingPath) {
    const std::string bad_index =
        WriteFile("badindex.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1 7\n");
    ExpectThrowsWith([&] { ReadOff(bad_index); }, bad_index);
    const std::string bad_number =
        WriteFile("badnum.off", "OFF\n3 1 0\n0 0 0\n1 zero 0\n1 1 0\n3 0 1 2\n");
    ExpectThrowsWith([&] { ReadOff(bad_number); }, bad_number);
    const std::string not_off = WriteFile("notoff.off", "ply\nformat ascii 1.0\n");
    ExpectThrowsWith([&] { ReadOff(not_off); }, not_off);
    const std::string short_face =
        WriteFile("shortface.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1\n");
    ExpectThrowsWith([&] { ReadOff(short_face); }, short_face);
    const std::string missing = ::testing::TempDir() + "regbench_mesh_test_missing.off";
    ExpectThrowsWith([&] { ReadOff(missing); }, missing);
}

TEST(ReadOff, RefusesCountsTheFileCannotHoldBeforeAllocating) {
    // 2e9 vertices need at least 6 bytes each ("0 0 0\n"); this file has 33 bytes, so the
    // header is refused before 2e9 x 3 doubles (48 GB) are allocated.
    const std::string path = WriteFile("huge.off", "OFF\n2000000000 1 0\n0 0 0\n3 0 0 0\n");
    const std::string err = testing::ErrorOf([&] { ReadOff(path); });
    EXPECT_NE(err.find(path), std::string::npos) << err;
    EXPECT_NE(err.find("header declares 2000000000 vertices and 1 faces, more than the file's 33 "
                       "bytes can hold"),
              std::string::npos)
        << err;
}

TEST(ReadOff, RefusesCoordinatesBeyondFloatRange) {
    // 1e300 is finite as a double but above FLT_MAX (3.4e38): the registration libraries
    // convert to float, so the vertex is refused at line 3 of the file.
    const std::string path =
        WriteFile("overflow.off", "OFF\n3 1 0\n0 0 1e300\n1 0 0\n1 1 0\n3 0 1 2\n");
    const std::string err = testing::ErrorOf([&] { ReadOff(path); });
    EXPECT_NE(
        err.find(path + ":3: OFF: vertex coordinate is not finite or does not fit in a float"),
        std::string::npos)
        << err;
}

TEST(NormalizeToUnitSphere, CentresBoundingBoxAndScalesMaxNormToOne) {
    Mesh mesh = ReadOff(WriteFile("quad2.off", kQuadOff));
    mesh.vertices = 7.0 * mesh.vertices;
    mesh.vertices.rowwise() += Eigen::RowVector3d(10, -5, 3);
    const Mesh unit = NormalizeToUnitSphere(mesh);
    EXPECT_NEAR(unit.vertices.rowwise().norm().maxCoeff(), 1.0, kTol);
    const Eigen::RowVector3d centre =
        0.5 * (unit.vertices.colwise().minCoeff() + unit.vertices.colwise().maxCoeff());
    EXPECT_LT(centre.norm(), kTol);
    EXPECT_EQ(unit.faces, mesh.faces);
}

TEST(SampleSurface, PointsLieOnTheSurfaceAndFollowArea) {
    // Two disjoint triangles: area 2 in plane z = 0 and area 0.5 in plane z = 5.
    Mesh mesh;
    mesh.vertices.resize(6, 3);
    mesh.vertices << 0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 5, 1, 0, 5, 0, 1, 5;
    mesh.faces.resize(2, 3);
    mesh.faces << 0, 1, 2, 3, 4, 5;
    std::mt19937_64 rng = MakePairRng(42, 0);
    const Eigen::Index n = 20000;
    const PointCloud points = SampleSurface(mesh, n, rng);
    ASSERT_EQ(points.rows(), n);
    int on_big = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
        const double x = points(i, 0), y = points(i, 1), z = points(i, 2);
        const bool big = std::abs(z) < kTol && x >= 0 && y >= 0 && x + y <= 2 + kTol;
        const bool small = std::abs(z - 5) < kTol && x >= 0 && y >= 0 && x + y <= 1 + kTol;
        ASSERT_TRUE(big || small) << points.row(i);
        on_big += big;
    }
    // P(big) = 2 / 2.5 = 0.8; binomial std = sqrt(0.8 * 0.2 / n) ~ 0.0028.
    EXPECT_NEAR(static_cast<double>(on_big) / n, 0.8, 0.015);
    // Uniform on a triangle: the mean is its centroid (2/3, 2/3) for the big one.
    Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
    for (Eigen::Index i = 0; i < n; ++i) {
        if (std::abs(points(i, 2)) < kTol) mean += points.row(i);
    }
    mean /= on_big;
    EXPECT_NEAR(mean(0), 2.0 / 3.0, 0.02);
    EXPECT_NEAR(mean(1), 2.0 / 3.0, 0.02);
}

TEST(SampleSurface, IsDeterministicForASeed) {
    const Mesh mesh = ReadOff(WriteFile("quad3.off", kQuadOff));
    std::mt19937_64 a = MakePairRng(7, 3), b = MakePairRng(7, 3), c = MakePairRng(7, 4);
    const PointCloud pa = SampleSurface(mesh, 100, a);
    EXPECT_EQ(pa, SampleSurface(mesh, 100, b));
    EXPECT_NE(pa, SampleSurface(mesh, 100, c));
}

TEST(SampleSurface, RejectsMeshWithoutArea) {
    Mesh mesh;
    mesh.vertices = PointCloud::Zero(3, 3);
    mesh.faces.resize(1, 3);
    mesh.faces << 0, 1, 2;
    std::mt19937_64 rng = MakePairRng(1, 0);
    EXPECT_THROW(SampleSurface(mesh, 10, rng), std::invalid_argument);
}

}  // namespace
}  // namespace regbench
