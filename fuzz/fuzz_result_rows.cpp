// libFuzzer target: the JSON readers of result rows (ReadResultRows, as report/compare/merge
// read them, with the depth limit and the row schema) and of --params (ParseJsonBounded).
#include "core/json_limits.hpp"
#include "fuzz/fuzz_input.hpp"
#include "runners/result_row.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    regbench::fuzz::RunReader(data, size, ".jsonl", [](const std::string& path) {
        for (const auto& row : regbench::ReadResultRows(path)) (void)regbench::ToJsonLine(row);
    });
    try {
        const std::string text(reinterpret_cast<const char*>(data), size);
        (void)regbench::ParseJsonBounded(text, "--params").dump();
    } catch (const std::exception&) {
    }
    return 0;
}
