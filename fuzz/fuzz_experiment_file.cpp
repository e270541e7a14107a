// libFuzzer target: experiment files (`reproduce --experiment FILE`, docs/reproducing.md):
// ReadExperimentFile (regular file, depth-limited JSON, every key by ParseConfig's rules), the
// protocol options each experiment generates with, and the checks across files. A refusal is a
// std::exception naming the file; anything else is a finding. Seeds: the paper's plan.
#include "experiments/experiment_file.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    regbench::fuzz::RunReader(data, size, ".json", [](const std::string& path) {
        const regbench::ExperimentFile file = regbench::ReadExperimentFile(path);
        for (const auto& s : file.experiments) (void)regbench::ProtocolOptionsOf(s);
        regbench::CheckExperimentFiles({file});
    });
    return 0;
}
