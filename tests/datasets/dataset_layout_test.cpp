#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "datasets/dataset.hpp"
#include "tests/testing/temp_dir_test.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;

using DatasetLayoutTest = testing::TempDirTest;

TEST_F(DatasetLayoutTest, RootWithSeveralDatasetsIsRefusedListingThem) {
    // The authors' data root: ModelNet40 (OFF tree), 7Scenes and ICL-NUIM side by side.
    fs::create_directories(dir_ / "ModelNet40" / "airplane" / "test");
    fs::create_directories(dir_ / "7scene" / "7-scenes-chess");
    fs::create_directories(dir_ / "icl_nuim" / "test");
    std::ofstream(dir_ / "icl_nuim" / "test" / "icl_nuim.h5") << "";
    for (const auto& call : {+[](const std::string& p) { OpenDataset(p, "all"); },
                             +[](const std::string& p) { DefaultSplit(p); }}) {
        try {
            call(dir_.string());
            FAIL() << "a root with several datasets was accepted";
        } catch (const std::invalid_argument& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("holds several datasets"), std::string::npos) << what;
            EXPECT_NE(what.find((dir_ / "ModelNet40").string()), std::string::npos) << what;
            EXPECT_NE(what.find((dir_ / "7scene").string()), std::string::npos) << what;
        }
    }
}

TEST_F(DatasetLayoutTest, FolderOfPointFilesDefaultsToSplitAll) {
    std::ofstream(dir_ / "a.xyz") << "0 0 0\n1 0 0\n0 1 0\n";
    EXPECT_EQ(DefaultSplit(dir_.string()), "all");
    EXPECT_EQ(DefaultSplit((dir_ / "a.xyz").string()), "all");
    // A single .h5 (DeepGMR's test files): OpenDataset accepts only "all" for it.
    std::ofstream((dir_ / "modelnet_clean.h5").string()) << "x";
    EXPECT_EQ(DefaultSplit((dir_ / "modelnet_clean.h5").string()), "all");
    fs::remove(dir_ / "modelnet_clean.h5");
    EXPECT_EQ(DefaultSplit("cgal"), "test");
    fs::create_directories(dir_ / "ModelNet40" / "airplane" / "test");
    EXPECT_EQ(DefaultSplit(dir_.string()), "test");  // one dataset below: its splits apply
}

}  // namespace
}  // namespace regbench
