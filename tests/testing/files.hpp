#pragma once
// File helpers the tests share: temporary folders, the shipped checkpoints, whole-file read and
// write, and the message of an expected exception. Standard library only, so every test folder
// can use it.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <stdexcept>
#include <string>

namespace regbench::testing {

/// `<temp>/regbench_<stem>_<pid><extension>` for `name` = "<stem><extension>", not created: a
/// path of this test process's own, so two ctest runs on one machine never share a file. The
/// extension stays last because readers pick the format by it.
inline std::filesystem::path TempPath(const std::string& name) {
    const std::filesystem::path n(name);
    return std::filesystem::temp_directory_path() /
           ("regbench_" + n.stem().string() + "_" + std::to_string(::getpid()) +
            n.extension().string());
}

/// An empty folder `<temp>/regbench_test_<name>_<pid>` (emptied if it exists): the pid keeps
/// two test binaries that ctest runs at once apart.
inline std::filesystem::path FreshTempDir(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("regbench_test_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

/// TempPath(name) as a folder, created when missing and otherwise kept as it is: the scratch
/// folder the tests of one file share in one process.
inline std::filesystem::path TempFolder(const std::string& name) {
    const std::filesystem::path dir = TempPath(name);
    std::filesystem::create_directories(dir);
    return dir;
}

/// The shipped checkpoint folder data/models/<model> of the source tree: under
/// $REGBENCH_SOURCE_DIR (ctest sets it), else under the working folder.
inline std::filesystem::path ShippedModel(const std::string& model) {
    const char* src = std::getenv("REGBENCH_SOURCE_DIR");
    return std::filesystem::path(src != nullptr ? src : ".") / "data" / "models" / model;
}

/// The whole file as bytes; empty if it cannot be opened.
inline std::string ReadBytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Writes `text` as the whole file (binary, truncating).
inline void WriteBytes(const std::filesystem::path& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
}

/// The what() of the std::exception `f` throws, or "" if it returns normally.
inline std::string ErrorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

}  // namespace regbench::testing
