// libFuzzer target: the HDF5 pair-file reader (ReadPairFile and CountPairs). The HDF5 library
// itself is not instrumented; the target checks regbench's validation on top of it.
#include "fuzz/fuzz_input.hpp"
#include "protocols/pair_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return regbench::fuzz::RunReader(data, size, ".h5", [](const std::string& path) {
        regbench::CountPairs(path);
        regbench::ReadPairFile(path);
    });
}
