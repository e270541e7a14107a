#pragma once
// A GoogleTest fixture with an empty folder of its own for the files a test writes.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace regbench::testing {

/// dir_ = `<temp>/regbench_<prefix>_<test name>`, created empty before each test and removed
/// after it. A fixture that overrides SetUp calls TempDirTest::SetUp() first.
class TempDirTest : public ::testing::Test {
protected:
    explicit TempDirTest(std::string prefix) : prefix_(std::move(prefix)) {}

    void SetUp() override {
        dir_ = std::filesystem::temp_directory_path() /
               ("regbench_" + prefix_ + "_" +
                std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    /// `name` inside dir_.
    std::string Path(const std::string& name) const { return (dir_ / name).string(); }

    std::filesystem::path dir_;

private:
    std::string prefix_;
};

}  // namespace regbench::testing
