// libFuzzer target: the readers behind `regbench import` (NNNN_src.xyz and NNNN_gt.txt): the
// same bytes are read as a cloud and as a 4x4 ground truth.
#include "fuzz/fuzz_input.hpp"
#include "protocols/xyz_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    regbench::fuzz::RunReader(data, size, "_src.xyz",
                              [](const std::string& path) { regbench::ReadXyz(path); });
    return regbench::fuzz::RunReader(
        data, size, "_gt.txt", [](const std::string& path) { regbench::ReadTransformTxt(path); });
}
