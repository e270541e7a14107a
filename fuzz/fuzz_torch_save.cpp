// libFuzzer target: ReadTorchSaveFile (import-checkpoint's reader of the authors' .pth files:
// zip archives and the legacy pickle stream, through regbench's restricted unpickler).
#include "fuzz/fuzz_input.hpp"
#include "networks/checkpoint/torch_save_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return regbench::fuzz::RunReader(data, size, ".pth", [](const std::string& path) {
        regbench::networks::ReadTorchSaveFile(path);
    });
}
