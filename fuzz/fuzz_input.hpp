#pragma once
// libFuzzer harness helper: regbench's readers take file names, so each input is written to a
// per-process temporary file first. Any std::exception is an accepted outcome (a refusal with a
// message); crashes, sanitizer reports, hangs and other exceptions are findings.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace regbench::fuzz {

/// Writes `data` to /tmp/regbench_fuzz_<pid><suffix> and returns the path.
inline std::string WriteInput(const std::uint8_t* data, std::size_t size, const char* suffix) {
    const std::string path =
        "/tmp/regbench_fuzz_" + std::to_string(::getpid()) + std::string(suffix);
    FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) std::abort();
    if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
    return path;
}

/// Runs `read(path)` and swallows the std::exception a refused input throws.
template <class Read>
int RunReader(const std::uint8_t* data, std::size_t size, const char* suffix, Read read) {
    const std::string path = WriteInput(data, size, suffix);
    try {
        read(path);
    } catch (const std::exception&) {
    }
    ::unlink(path.c_str());
    return 0;
}

}  // namespace regbench::fuzz
