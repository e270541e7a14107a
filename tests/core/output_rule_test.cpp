// The output rule's refusals that need no CLI (core/output_rule.hpp), issue 55: a folder output
// that is not a folder of its own, and an existing output another process is writing.
#include "core/output_rule.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "tests/testing/files.hpp"

namespace regbench {
namespace {
namespace fs = std::filesystem;

using testing::ErrorOf;

/// The message of the OutputPathError `f` throws ("" when it throws none or another type).
std::string PathErrorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const OutputPathError& e) {
        return e.what();
    } catch (...) {
    }
    return "";
}

// Item 1: `import-checkpoint --out . --force` emptied the current folder. Expected: ".", "..",
// paths ending in them, the current folder and the folders above it are OutputPathErrors (the
// CLI's exit 2) naming the path, for every folder output, continued or replaced; a folder of
// its own (a trailing slash allowed) passes, and a file output keeps its own rule.
TEST(OutputRule, AFolderOutputMustBeAFolderOfItsOwn) {
    const fs::path dir = testing::FreshTempDir("output_rule_dots");
    const fs::path sub = dir / "sub";
    fs::create_directories(sub);
    const fs::path before = fs::current_path();
    fs::current_path(sub);
    OutputRule replace;
    replace.folder = true;
    replace.replace = true;
    OutputRule continues;
    continues.folder = true;
    continues.continues = true;
    const std::vector<std::pair<std::string, std::string>> refused = {
        {".", "not '.'"},
        {"./", "not '.'"},
        {"..", "not '..'"},
        {"../", "not '..'"},
        {"../sub/.", "not '.'"},
        {sub.string(), "is the current folder"},
        {"../sub", "is the current folder"},
        {dir.string(), "holds the current folder"},
        {"/", "holds the current folder"},
    };
    for (const OutputRule& rule : {replace, continues}) {
        for (const auto& [path, why] : refused) {
            const std::string out = path;  // a copy: lambdas capture no structured binding
            const std::string e = PathErrorOf([&] { CheckOutputRule(out, {}, rule); });
            EXPECT_EQ(e.rfind(out + ": ", 0), 0u) << out << ": " << e;
            EXPECT_NE(e.find(why), std::string::npos) << out << ": " << e;
        }
        EXPECT_EQ(ErrorOf([&] { CheckOutputRule("own/", {}, rule); }), "");
        EXPECT_EQ(ErrorOf([&] { CheckOutputRule((dir / "other").string(), {}, rule); }), "");
    }
    // A file output named "." is a directory, refused as before (not a usage error).
    EXPECT_EQ(PathErrorOf([&] { CheckOutputRule(".", {}, OutputRule{true}); }), "");
    fs::current_path(before);
    fs::remove_all(dir);
}

// Item 8: `run --out X.part` while another run writes X suggested --force. Expected: the
// refusal names the writer's pid.
TEST(OutputRule, AnOutputBeingWrittenNamesItsWriter) {
    const fs::path dir = testing::FreshTempDir("output_rule_busy");
    const std::string out = (dir / "r.jsonl").string();
    testing::WriteBytes(out + ".part", "{}\n");
    int ready[2];
    ASSERT_EQ(::pipe(ready), 0);
    const pid_t pid = fork();
    if (pid == 0) {
        const OutputLock lock(out);
        const char byte = 1;
        (void)::write(ready[1], &byte, 1);
        ::pause();
        _exit(0);
    }
    char byte = 0;
    ASSERT_EQ(::read(ready[0], &byte, 1), 1);
    for (const std::string& path : {out + ".part", out}) {
        if (path == out) testing::WriteBytes(out, "{}\n");
        const std::string e = ErrorOf([&] { CheckOutputRule(path, {}, OutputRule{}); });
        EXPECT_NE(e.find(path + ": is being written by another regbench process (pid " +
                         std::to_string(pid) + ")"),
                  std::string::npos)
            << e;
    }
    ::kill(pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
    // The writer gone, the refusal is the plain one again.
    const std::string e = ErrorOf([&] { CheckOutputRule(out, {}, OutputRule{}); });
    EXPECT_NE(e.find("already exists"), std::string::npos) << e;
    ::close(ready[0]);
    ::close(ready[1]);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench
