#pragma once
// Merging shard results (Slurm array tasks, GNU parallel jobs) into one checked result file.
#include <string>
#include <vector>

#include "runners/runner.hpp"

namespace regbench {

struct MergeOptions {
    std::vector<std::string> inputs;  ///< shard results (JSONL), any order
    std::string out_path;             ///< merged JSONL, written atomically
    std::string pairs_path;           ///< the pair file every shard ran on
    std::vector<MethodSpec> methods;  ///< the methods (resolved parameters) every shard ran
};

/// Checks every row (fields, pair-file hash, method and parameters, as --resume does), refuses
/// duplicates naming both file:line places, and refuses an incomplete set naming the missing
/// (pair, method) rows. Writes the rows sorted by (pair, method order), exactly as one
/// unsharded run orders them. Returns the number of rows. Throws std::runtime_error.
std::size_t MergeResults(const MergeOptions& options);

}  // namespace regbench
