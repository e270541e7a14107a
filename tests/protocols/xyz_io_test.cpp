#include "protocols/xyz_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "protocols/pair_protocols.hpp"
#include "tests/protocols/test_shapes.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/same_pairs.hpp"

namespace regbench {
namespace {

TEST(XyzIo, ExportThenImportRoundTripsExactly) {
    const std::string dir = testing::FreshTempDir("xyz_round_trip");
    const PairSet set =
        GeneratePairs(test::TestShapes(), DefaultProtocolOptions(Protocol::kJitter), 3, 3);
    ExportXyz(set, dir);
    EXPECT_TRUE(std::filesystem::exists(dir + "/0002_gt.txt"));
    const PairSet back = ImportXyzDir(dir, 0.1);
    ASSERT_EQ(back.pairs.size(), 3u);
    // Same radius -> same overlap labels as the generator computed.
    testing::ExpectSamePairs(back, set);
    for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(back.pairs[k].shape, PairStem(k));
    EXPECT_EQ(back.provenance.at("params").at("eta").get<double>(), 0.1);
    std::filesystem::remove_all(dir);
}

// `regbench export pairs.h5 --out ex/` failed ("ex/: cannot move the export into place:
// Directory not empty"): its temporary folder went inside ex/. Expected: the same export as
// without the slash, and no temporary left in the folder or beside it (only the 3 pairs' files).
TEST(XyzIo, ExportIntoAFolderNamedWithATrailingSlash) {
    const std::string parent = testing::FreshTempDir("xyz_slash");
    const std::string dir = parent + "/ex";
    const PairSet set =
        GeneratePairs(test::TestShapes(), DefaultProtocolOptions(Protocol::kJitter), 3, 3);
    ExportXyz(set, dir + "/");
    EXPECT_EQ(ImportXyzDir(dir, 0.1).pairs.size(), 3u);
    std::size_t entries = 0;
    for (const auto& e : std::filesystem::directory_iterator(parent)) {
        EXPECT_EQ(e.path().filename(), "ex") << "left beside the export: " << e.path();
        ++entries;
    }
    EXPECT_EQ(entries, 1u);
    std::filesystem::remove_all(parent);
}

TEST(XyzIo, PlyExportHasHeaderAndAllPoints) {
    const std::string dir = testing::FreshTempDir("ply_export");
    const PairSet set = GeneratePairs(test::TestShapes(), ProtocolOptions{}, 3, 1);
    ExportPly(set, dir);
    std::ifstream in(dir + "/0000_src.ply");
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "ply");
    int rows = 0;
    bool header = true;
    while (std::getline(in, line)) {
        if (!header) ++rows;
        if (line == "end_header") header = false;
    }
    EXPECT_EQ(rows, 717);
    std::filesystem::remove_all(dir);
}

// Issue 27: 0001_src.xyz and 00001_src.xyz both parse as pair 1's source; one was read and
// the other ignored without a word. Expected: a refusal naming both files.
TEST(XyzIo, AmbiguousPairNamesAreRefused) {
    const std::string dir = testing::FreshTempDir("xyz_ambiguous");
    const PairSet set =
        GeneratePairs(test::TestShapes(), DefaultProtocolOptions(Protocol::kJitter), 2, 3);
    ExportXyz(set, dir);
    std::filesystem::copy_file(dir + "/0001_src.xyz", dir + "/00001_src.xyz");
    const std::string err = testing::ErrorOf([&] { ImportXyzDir(dir, 0.1); });
    EXPECT_NE(err.find("00001_src.xyz and 0001_src.xyz both name pair 1"), std::string::npos)
        << err;
    std::filesystem::remove_all(dir);
}

TEST(XyzIo, MalformedFilesAreRejectedWithFileAndLine) {
    const std::string dir = testing::FreshTempDir("xyz_bad");
    testing::WriteBytes(dir + "/0000_src.xyz", "0 0 0\n1 0 0\n0 1 zero\n");
    testing::WriteBytes(dir + "/0000_tgt.xyz", "0 0 0\n1 0 0\n0 1 0\n");
    testing::WriteBytes(dir + "/0000_gt.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    EXPECT_NE(
        testing::ErrorOf([&] { ImportXyzDir(dir, 0.1); }).find("0000_src.xyz:3: not a number"),
        std::string::npos)
        << testing::ErrorOf([&] { ImportXyzDir(dir, 0.1); });

    testing::WriteBytes(dir + "/0000_src.xyz", "0 0 0\n1 0 0 5\n");
    EXPECT_NE(testing::ErrorOf([&] {
                  ImportXyzDir(dir, 0.1);
              }).find("0000_src.xyz:2: expected 3 numbers"),
              std::string::npos);

    testing::WriteBytes(dir + "/0000_src.xyz", "# comment\n\n0 0 0\n1 0 0\n0 1 0\n");
    EXPECT_NO_THROW(ImportXyzDir(dir, 0.1));

    testing::WriteBytes(dir + "/0000_gt.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n");
    EXPECT_NE(
        testing::ErrorOf([&] { ImportXyzDir(dir, 0.1); }).find("0000_gt.txt:3: expected 4 rows"),
        std::string::npos);
    testing::WriteBytes(dir + "/0000_gt.txt", "2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    EXPECT_NE(testing::ErrorOf([&] { ImportXyzDir(dir, 0.1); }).find("not a rotation"),
              std::string::npos);
    testing::WriteBytes(dir + "/0000_gt.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n");
    EXPECT_NE(testing::ErrorOf([&] { ImportXyzDir(dir, 0.1); }).find("0000_gt.txt:4: last row"),
              std::string::npos);

    // A pair number with a missing partner file, and a gap in the numbering.
    testing::WriteBytes(dir + "/0000_gt.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    testing::WriteBytes(dir + "/0001_src.xyz", "0 0 0\n");
    EXPECT_NE(testing::ErrorOf([&] { ImportXyzDir(dir, 0.1); }).find("0001_tgt.xyz: no such file"),
              std::string::npos);
    std::filesystem::remove(dir + "/0001_src.xyz");
    testing::WriteBytes(dir + "/0002_src.xyz", "0 0 0\n");
    EXPECT_NE(testing::ErrorOf([&] { ImportXyzDir(dir, 0.1); }).find("0001_src.xyz: missing"),
              std::string::npos);
    std::filesystem::remove_all(dir);
    EXPECT_NE(testing::ErrorOf([&] { ImportXyzDir(dir, 0.1); }).find("not a directory"),
              std::string::npos);
}

}  // namespace
}  // namespace regbench
