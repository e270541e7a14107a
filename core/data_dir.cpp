#include "core/data_dir.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>

#include "core/version.hpp"

namespace regbench {

std::string DataDir() {
    namespace fs = std::filesystem;
    if (const char* d = std::getenv("REGBENCH_DATA_DIR"); d != nullptr && *d != '\0') return d;
    if (const char* s = std::getenv("REGBENCH_SOURCE_DIR"); s != nullptr && *s != '\0') {
        return (fs::path(s) / "data").string();
    }
    const fs::path built_from = fs::path(RegbenchSourceDir()) / "data";
    std::error_code ec;
    if (fs::is_directory(built_from, ec)) return built_from.string();
    return "data";
}

}  // namespace regbench
