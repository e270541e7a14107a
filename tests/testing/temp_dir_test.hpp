#pragma once
// A GoogleTest fixture with an empty folder of its own for the files a test writes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace regbench::testing {

/// dir_ = `<temp>/regbench_<test suite>_<test name>_<pid>` (the pid keeps concurrent ctest runs
/// apart), created empty before each test and
/// removed after it. A fixture that overrides SetUp calls TempDirTest::SetUp() first; one that
/// adds nothing can be an alias (using MyTest = testing::TempDirTest).
class TempDirTest : public ::testing::Test {
protected:
    void SetUp() override {
        const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = std::filesystem::temp_directory_path() /
               (std::string("regbench_") + test->test_suite_name() + "_" + test->name() + "_" +
                std::to_string(::getpid()));
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    /// `name` inside dir_.
    std::string Path(const std::string& name) const { return (dir_ / name).string(); }

    std::filesystem::path dir_;
};

}  // namespace regbench::testing
