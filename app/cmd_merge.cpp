// `regbench merge`: shard results into one complete, checked result file.
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "app/cli_params.hpp"
#include "app/commands.hpp"
#include "runners/merge.hpp"

namespace regbench::app {

namespace {

void SetupMergeCommand(CLI::App* cmd) {
    auto o = std::make_shared<MergeOptions>();
    auto methods = std::make_shared<std::string>();
    auto params = std::make_shared<std::string>();
    cmd->add_option("results", o->inputs, "Shard result files (JSONL)")->required();
    cmd->add_option("--out", o->out_path, "Merged JSONL (written atomically)")->required();
    cmd->add_option("--pairs", o->pairs_path, "The pair file the shards ran on")->required();
    cmd->add_option("--methods", *methods, "The methods the shards ran (as given to run)")
        ->required();
    cmd->add_option("--params", *params, "The --params the shards ran with (JSON)");
    cmd->callback([o, methods, params] {
        MergeOptions options = *o;
        const nlohmann::json p = ParseParamsOption(*params);
        options.methods = ParseMethodSpecs(*methods, p);
        const std::size_t n = MergeResults(options);
        std::cerr << "merge: wrote " << n << " rows from " << options.inputs.size() << " files to "
                  << options.out_path << "\n";
    });
}

[[maybe_unused]] const bool kMergeRegistered = RegisterCommand(
    {"merge", "Merge shard results; every (pair, method) exactly once, or an error naming it",
     SetupMergeCommand});
}  // namespace

}  // namespace regbench::app
