// libFuzzer target: ReadPointFile on a .pcd file (header checks, then the reader).
#include "datasets/point_file.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return regbench::fuzz::RunReader(data, size, ".pcd", [](const std::string& path) {
        regbench::Normals normals;
        regbench::ReadPointFile(path, &normals);
    });
}
