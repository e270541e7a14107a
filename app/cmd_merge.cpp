// `regbench merge`: shard results into one complete, checked result file.
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "app/cli_params.hpp"
#include "app/commands.hpp"
#include "core/output_rule.hpp"
#include "runners/merge.hpp"

namespace regbench::app {

namespace {

void SetupMergeCommand(CLI::App* cmd) {
    auto o = std::make_shared<MergeOptions>();
    auto m = std::make_shared<MethodArgs>();
    auto force = std::make_shared<bool>(false);
    cmd->add_option("results", o->inputs, "Shard result files (JSONL)")->required();
    cmd->add_option("--out", o->out_path, "Merged JSONL (written atomically)")->required();
    cmd->add_option("--pairs", o->pairs_path, "The pair file the shards ran on")->required();
    m->Add(cmd, "The methods the shards ran (as given to run)",
           "The --params the shards ran with (JSON)");
    cmd->add_flag("--force", *force, "Replace an existing --out");
    cmd->callback([o, m, force] {
        // The one output rule (docs/usage.md, "Outputs"); the merge takes the lock.
        std::vector<std::string> inputs = o->inputs;
        inputs.push_back(o->pairs_path);
        CheckOutputRule(o->out_path, inputs, OutputRule{*force});
        MergeOptions options = *o;
        options.methods = m->Specs();
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
