#include "datasets/point_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <tuple>
#include <vector>

#include "tests/datasets/test_files.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

using testing::ExpectThrowsWith;
using testing::FreshDir;
using testing::WriteText;

constexpr double kTol = 1e-9;

constexpr const char* kPlyAscii =
    "ply\nformat ascii 1.0\nelement vertex 3\n"
    "property float x\nproperty float y\nproperty float z\n"
    "property float nx\nproperty float ny\nproperty float nz\nend_header\n"
    "0 0 0 0 0 1\n1 2 3 0 1 0\n-1 0.5 2 1 0 0\n";

/// Writes `text` as `dir`/`name` and expects ReadPointFile to refuse it with a message naming the
/// file's path followed by `where` (":line: reason", or nothing).
void ExpectRefused(const std::filesystem::path& dir, const std::string& name,
                   const std::string& text, const std::string& where = "") {
    SCOPED_TRACE(name);
    const std::string path = WriteText(dir / name, text);
    ExpectThrowsWith([&] { ReadPointFile(path); }, path + where);
}

TEST(ReadPointFile, ReadsXyzWithCommentsAndNormals) {
    const auto dir = FreshDir();
    const std::string path =
        WriteText(dir / "a.xyz", "# header comment\n1 2 3 0 0 1\n\n4,5,6,0,1,0\n7 8 9 1 0 0 # c\n");
    Normals normals;
    const PointCloud p = ReadPointFile(path, &normals);
    ASSERT_EQ(p.rows(), 3);
    EXPECT_EQ(p.row(1), Eigen::RowVector3d(4, 5, 6));
    ASSERT_EQ(normals.rows(), 3);
    EXPECT_EQ(normals.row(2), Eigen::RowVector3d(1, 0, 0));
    // Without normals on every line, none are reported.
    Normals none;
    ReadPointFile(WriteText(dir / "b.xyz", "1 2 3\n4 5 6 0 0 1\n"), &none);
    EXPECT_EQ(none.rows(), 0);
}

TEST(ReadPointFile, RejectsBadXyzLineWithFileAndLine) {
    const auto dir = FreshDir();
    ExpectRefused(dir, "bad.xyz", "1 2 3\n4 5 6\n7 eight 9\n", ":3");
    ExpectRefused(dir, "short.xyz", "1 2 3\n4 5\n", ":2");
    ExpectRefused(dir, "empty.xyz", "# nothing\n");
    const std::string missing = (dir / "missing.xyz").string();
    ExpectThrowsWith([&] { ReadPointFile(missing); }, missing);
    ExpectRefused(dir, "cloud.obj", "v 1 2 3\n");
}

TEST(ReadPointFile, ReadsPlyAndPcdThroughOpen3D) {
    const auto dir = FreshDir();
    Normals normals;
    const PointCloud ply = ReadPointFile(WriteText(dir / "a.ply", kPlyAscii), &normals);
    ASSERT_EQ(ply.rows(), 3);
    EXPECT_NEAR((ply.row(2) - Eigen::RowVector3d(-1, 0.5, 2)).norm(), 0.0, kTol);
    ASSERT_EQ(normals.rows(), 3);
    EXPECT_NEAR((normals.row(1) - Eigen::RowVector3d(0, 1, 0)).norm(), 0.0, kTol);
    const PointCloud pcd = ReadPointFile(WriteText(dir / "a.pcd",
                                                   "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\n"
                                                   "TYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                                                   "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\n"
                                                   "DATA ascii\n1 2 3\n4 5 6\n"));
    ASSERT_EQ(pcd.rows(), 2);
    EXPECT_NEAR((pcd.row(1) - Eigen::RowVector3d(4, 5, 6)).norm(), 0.0, kTol);
}

// Issue 27 item 5: NaN points are refused or dropped with a count, a flag (align
// --nan-points) chooses. Files written here: a PLY with 1 NaN point of 4 and a PCD with 2 of 3
// (NaN and inf), so the expected counts are those written, and the kept points are the finite
// rows in file order.
TEST(ReadPointFile, NonFinitePointsAreDroppedOrRefusedAsChosen) {
    const auto dir = FreshDir();
    const std::string ply = WriteText(dir / "nan.ply",
                                      "ply\nformat ascii 1.0\nelement vertex 4\n"
                                      "property float x\nproperty float y\nproperty float z\n"
                                      "end_header\n0 0 0\nnan 1 1\n1 2 3\n4 5 6\n");
    const std::string pcd = WriteText(dir / "nan.pcd",
                                      "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                                      "COUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
                                      "POINTS 3\nDATA ascii\n1 2 3\nnan nan nan\n4 inf 6\n");
    const PointCloud kept = ReadPointFile(ply, nullptr, NonFinitePoints::kDrop);
    ASSERT_EQ(kept.rows(), 3);
    EXPECT_NEAR((kept.row(1) - Eigen::RowVector3d(1, 2, 3)).norm(), 0.0, kTol);
    EXPECT_EQ(ReadPointFile(pcd).rows(), 1);  // the default drops
    ExpectThrowsWith([&] { ReadPointFile(ply, nullptr, NonFinitePoints::kRefuse); },
                     ply + ": 1 of 4 points have NaN or Inf coordinates");
    ExpectThrowsWith([&] { ReadCloudFile(pcd, NonFinitePoints::kRefuse); },
                     pcd + ": 2 of 3 points have NaN or Inf coordinates");
}

TEST(ReadPointFile, RejectsTruncatedPlyNamingPath) {
    const auto dir = FreshDir();
    std::string text = kPlyAscii;
    text = text.substr(0, text.find("1 2 3"));  // header promises 3 vertices, 1 present
    ExpectRefused(dir, "truncated.ply", text);
    ExpectRefused(dir, "garbage.ply", "this is not a ply file\n");
}

// Regression for a fuzz_ply find (UBSan: a negative body size converted to long long): a header
// whose "end_header" is the file's last bytes, without a newline, with a body-less vertex count.
TEST(ReadPointFile, RefusesAHeaderEndingAtTheEndOfTheFile) {
    ExpectRefused(FreshDir(), "header_only.ply",
                  "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\n"
                  "property float y\nproperty float z\nend_header");
}

// Regression for a fuzz_ply find (SEGV inside Open3D's PLY reader): a property line with no
// type and name is refused by regbench's own header check, naming the file and line.
TEST(ReadPointFile, RefusesAPlyPropertyWithoutTypeAndName) {
    ExpectRefused(FreshDir(), "bare_property.ply",
                  "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                  "property float y\nproperty\nend_header\n0 0 0\n1 0 0\n0 1 0\n",
                  ":6");
}

// Regression for a fuzz_pcd find (SEGV inside Open3D's PCD reader on a field with COUNT 0,
// fuzz/corpus/pcd/count-zero.pcd): regbench's own PCD header check refuses it and the other
// per-field inconsistencies Open3D would index out of bounds, naming the file and line. The
// expected lines are counted by hand in the literals below.
TEST(ReadPointFile, RefusesInconsistentPcdFieldLists) {
    const auto dir = FreshDir();
    const std::string body = "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n";
    const std::vector<std::tuple<std::string, std::string, std::string>> cases = {
        {"count0.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 0\n", ":4: PCD COUNT must"},
        {"size3.pcd", "FIELDS x y z\nSIZE 4 3 4\nTYPE F F F\nCOUNT 1 1 1\n", ":2: PCD SIZE must"},
        {"typeq.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F Q F\nCOUNT 1 1 1\n", ":3: PCD TYPE must"},
        {"short_size.pcd", "FIELDS x y z\nSIZE 4 4\nTYPE F F F\nCOUNT 1 1 1\n",
         ":1: PCD header lists 3 FIELDS but 2 SIZE"},
        {"long_count.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1 1\n",
         ":1: PCD header lists 3 FIELDS but 4 COUNT"},
        {"no_type.pcd", "FIELDS x y z\nSIZE 4 4 4\n", ":1: PCD header lists 3 FIELDS but 0 TYPE"},
        {"no_fields.pcd", "SIZE 4 4 4\nTYPE F F F\n", ": PCD header has no FIELDS line"},
    };
    for (const auto& [name, header, reason] : cases)
        ExpectRefused(dir, name, header + body, reason);
    ExpectRefused(dir, "data.pcd",
                  "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA binaqy\n1234",
                  ":5: PCD DATA must");
    // No POINTS line (fuzz_pcd: Open3D then allocated from an uninitialised count, 33 GB).
    ExpectRefused(dir, "no_points.pcd",
                  "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\n"
                  "HEIGHT 1\nDATA ascii\n0 0 0\n1 0 0\n0 1 0\n",
                  ": PCD header has no POINTS line");
}

TEST(ReadCloudFile, ReadsOffVerticesAndPointFiles) {
    // A hand-written triangle: the three vertices in file order, faces ignored.
    const auto path = regbench::testing::TempPath("cloud_tri.off");
    std::ofstream(path) << "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    const PointCloud p = ReadCloudFile(path.string());
    ASSERT_EQ(p.rows(), 3);
    EXPECT_EQ(p(1, 0), 1.0);
    EXPECT_EQ(p(2, 1), 1.0);
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace regbench
