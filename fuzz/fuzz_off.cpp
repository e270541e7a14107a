// libFuzzer target: the OFF mesh reader (ModelNet40's format).
#include "fuzz/fuzz_input.hpp"
#include "protocols/mesh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return regbench::fuzz::RunReader(data, size, ".off",
                                     [](const std::string& path) { regbench::ReadOff(path); });
}
