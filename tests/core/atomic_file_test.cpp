#include "core/atomic_file.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>

#include "core/file_lock.hpp"
#include "tests/testing/file_size_limit.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;

using testing::RunUnderFileSizeLimit;

TEST(AtomicFile, WritesAndReplacesAtomically) {
    const fs::path dir = testing::FreshTempDir("replace");
    const std::string path = (dir / "out.txt").string();
    WriteFileAtomic(path, "first\n");
    WriteFileAtomic(path, "second\n");
    EXPECT_EQ(testing::ReadBytes(path), "second\n");
    // Only the final file remains: no temporaries.
    EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
    fs::remove_all(dir);
}

TEST(AtomicFile, FileSizeLimitLeavesNoFileAndNoSignal) {
    const fs::path dir = testing::FreshTempDir("fsize");
    const std::string path = (dir / "big.txt").string();
    const int status =
        RunUnderFileSizeLimit(4096, path, [&] { WriteFileAtomic(path, std::string(100000, 'x')); });
    ASSERT_TRUE(WIFEXITED(status)) << "child died by a signal";
    EXPECT_EQ(WEXITSTATUS(status), 3) << "expected an error naming " << path;
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(fs::is_empty(dir)) << "temporary file left behind";
    fs::remove_all(dir);
}

TEST(AtomicFile, FailedWriteKeepsThePreviousFile) {
    const fs::path dir = testing::FreshTempDir("keep");
    const std::string path = (dir / "r.txt").string();
    WriteFileAtomic(path, "old\n");
    const int status =
        RunUnderFileSizeLimit(1024, path, [&] { WriteFileAtomic(path, std::string(50000, 'y')); });
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 3);
    EXPECT_EQ(testing::ReadBytes(path), "old\n");
    fs::remove_all(dir);
}

TEST(CheckOutputPath, RefusesDirectoriesDevicesInputsAndMissingDirs) {
    const fs::path dir = testing::FreshTempDir("check");
    const std::string input = (dir / "in.h5").string();
    WriteFileAtomic(input, "data");
    EXPECT_NE(testing::ErrorOf([&] { CheckOutputPath(dir.string()); }).find("is a directory"),
              std::string::npos);
    EXPECT_NE(testing::ErrorOf([&] { CheckOutputPath("/dev/null"); }).find("not a regular file"),
              std::string::npos);
    EXPECT_NE(
        testing::ErrorOf([&] { CheckOutputPath(input, {input}); }).find("same file as the input"),
        std::string::npos);
    // Another name for the same inode is the same file.
    const std::string link = (dir / "link.h5").string();
    fs::create_hard_link(input, link);
    EXPECT_NE(testing::ErrorOf([&] { CheckOutputPath(link, {input}); }).find("same file"),
              std::string::npos);
    EXPECT_NE(testing::ErrorOf([&] {
                  CheckOutputPath((dir / "no/such/out").string());
              }).find("does not exist"),
              std::string::npos);
    EXPECT_EQ(testing::ErrorOf([&] { CheckOutputPath((dir / "new.txt").string(), {input}); }), "");
    // The writer itself refuses too, and /dev/null is left alone.
    EXPECT_THROW(WriteFileAtomic("/dev/null", "x"), std::runtime_error);
    EXPECT_TRUE(fs::is_character_file("/dev/null"));
    fs::remove_all(dir);
}

TEST(OutputLock, SecondHolderIsRefusedWithThePid) {
    const fs::path dir = testing::FreshTempDir("lock");
    const std::string out = (dir / "r.jsonl").string();
    {
        const OutputLock first(out);
        const std::string err = testing::ErrorOf([&] { OutputLock second(out); });
        EXPECT_NE(err.find("pid " + std::to_string(getpid())), std::string::npos) << err;
        // Another process is refused as well (flock locks are per open file description).
        const pid_t pid = fork();
        if (pid == 0) {
            try {
                OutputLock other(out);
            } catch (const std::runtime_error&) {
                _exit(7);
            }
            _exit(0);
        }
        int status = 0;
        waitpid(pid, &status, 0);
        ASSERT_TRUE(WIFEXITED(status));
        EXPECT_EQ(WEXITSTATUS(status), 7);
    }
    // Released: the next writer gets it, and no lock file is left behind afterwards.
    { const OutputLock again(out); }
    EXPECT_FALSE(fs::exists(out + ".lock"));
    fs::remove_all(dir);
}

// `export --out dir/` failed with "dir/.lock: cannot create lock file: No such file or
// directory": a folder named with a trailing slash is the same output as without it. Expected
// (from the path rules, not the code): the lock is "<dir>.lock" beside the folder, taken while
// the folder does not exist yet, and "dir" and "dir//" are refused as the same output.
TEST(OutputLock, AFolderWithATrailingSlashLocksBesideIt) {
    const fs::path dir = testing::FreshTempDir("lock_slash");
    const std::string folder = (dir / "xyz").string();
    {
        const OutputLock lock(folder + "/");
        EXPECT_EQ(lock.lock_path(), folder + ".lock");
        EXPECT_TRUE(fs::exists(folder + ".lock"));
        EXPECT_FALSE(fs::exists(folder));
        EXPECT_NE(testing::ErrorOf([&] { OutputLock second(folder); }), "");
        EXPECT_NE(testing::ErrorOf([&] { OutputLock third(folder + "//"); }), "");
    }
    fs::remove_all(dir);
}

// Issue 27, item 1: the lock belongs to the pid that took it. A forked child that destroys
// the parent's OutputLock object (as an exception unwinding through the parent's frames did)
// must leave the file; the expected facts are that the lock file still exists and that a
// second writer is still refused, exactly as before the child ran.
TEST(OutputLock, AForkedChildDestroyingTheLockLeavesItToTheParent) {
    const fs::path dir = testing::FreshTempDir("lock_owner");
    const std::string out = (dir / "r.jsonl").string();
    auto lock = std::make_unique<OutputLock>(out);
    const pid_t pid = fork();
    if (pid == 0) {
        lock.reset();  // the destructor runs in the child
        _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    EXPECT_TRUE(fs::exists(out + ".lock"));
    EXPECT_NE(testing::ErrorOf([&] { OutputLock second(out); }), "");
    lock.reset();  // the owner removes it
    EXPECT_FALSE(fs::exists(out + ".lock"));
    fs::remove_all(dir);
}

// Issue 27, item 2: a link pre-placed at OUT.lock (symbolic or hard, to an input or any
// other file) is refused naming the lock path, and the file it points to keeps its bytes.
// The expected bytes are the ones this test wrote into the target before taking the lock.
TEST(OutputLock, RefusesLinksAtTheLockPathAndLeavesTheirTargets) {
    const fs::path dir = testing::FreshTempDir("lock_links");
    const std::string out = (dir / "r.jsonl").string();
    const fs::path target = dir / "input.h5";
    testing::WriteBytes(target, "precious input bytes\n");
    for (const bool hard : {false, true}) {
        fs::remove(out + ".lock");
        if (hard) {
            fs::create_hard_link(target, out + ".lock");
        } else {
            fs::create_symlink(target, out + ".lock");
        }
        const std::string err = testing::ErrorOf([&] { OutputLock lock(out); });
        EXPECT_NE(err.find(out + ".lock"), std::string::npos) << err;
        EXPECT_EQ(testing::ReadBytes(target), "precious input bytes\n") << "hard=" << hard;
    }
    // A FIFO there is refused too (opening it must not block).
    fs::remove(out + ".lock");
    ASSERT_EQ(::mkfifo((out + ".lock").c_str(), 0644), 0);
    EXPECT_NE(testing::ErrorOf([&] { OutputLock lock(out); }).find("not a regular file"),
              std::string::npos);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench
