// libFuzzer target: the OFF mesh reader (ModelNet40's format).
#include "datasets/off_reader.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return regbench::fuzz::RunReader(data, size, ".off",
                                     [](const std::string& path) { regbench::ReadOff(path); });
}
