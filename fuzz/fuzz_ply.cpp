// libFuzzer target: ReadPointFile on a .ply file (header checks, then the reader).
#include "fuzz/fuzz_input.hpp"
#include "protocols/point_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return regbench::fuzz::RunReader(data, size, ".ply", [](const std::string& path) {
        regbench::Normals normals;
        regbench::ReadPointFile(path, &normals);
    });
}
