#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "datasets/dataset.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;

class DatasetLayoutTest : public ::testing::Test {
protected:
    void SetUp() override {
        root_ = fs::temp_directory_path() /
                ("regbench_layout_" +
                 std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        fs::remove_all(root_);
        fs::create_directories(root_);
    }
    void TearDown() override { fs::remove_all(root_); }
    fs::path root_;
};

TEST_F(DatasetLayoutTest, RootWithSeveralDatasetsIsRefusedListingThem) {
    // The authors' data root: ModelNet40 (OFF tree), 7Scenes and ICL-NUIM side by side.
    fs::create_directories(root_ / "ModelNet40" / "airplane" / "test");
    fs::create_directories(root_ / "7scene" / "7-scenes-chess");
    fs::create_directories(root_ / "icl_nuim" / "test");
    std::ofstream(root_ / "icl_nuim" / "test" / "icl_nuim.h5") << "";
    for (const auto& call : {+[](const std::string& p) { OpenDataset(p, "all"); },
                             +[](const std::string& p) { DefaultSplit(p); }}) {
        try {
            call(root_.string());
            FAIL() << "a root with several datasets was accepted";
        } catch (const std::invalid_argument& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("holds several datasets"), std::string::npos) << what;
            EXPECT_NE(what.find((root_ / "ModelNet40").string()), std::string::npos) << what;
            EXPECT_NE(what.find((root_ / "7scene").string()), std::string::npos) << what;
        }
    }
}

TEST_F(DatasetLayoutTest, FolderOfPointFilesDefaultsToSplitAll) {
    std::ofstream(root_ / "a.xyz") << "0 0 0\n1 0 0\n0 1 0\n";
    EXPECT_EQ(DefaultSplit(root_.string()), "all");
    EXPECT_EQ(DefaultSplit((root_ / "a.xyz").string()), "all");
    EXPECT_EQ(DefaultSplit("cgal"), "test");
    fs::create_directories(root_ / "ModelNet40" / "airplane" / "test");
    EXPECT_EQ(DefaultSplit(root_.string()), "test");  // one dataset below: its splits apply
}

}  // namespace
}  // namespace regbench
