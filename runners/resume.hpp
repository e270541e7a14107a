#pragma once
// What an existing results file must satisfy before its rows are kept (--resume) or merged:
// rows from another pair file, other methods or parameters, duplicates or rows missing fields
// are refused with file:line, never mixed into a result.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "runners/runner.hpp"

namespace regbench {

/// Identity of a pair file's bytes: "fnv1a64:<16 hex digits>". Rows carry it in data.pairs_hash.
/// (An identity check, not a security hash.) Throws naming the path when it cannot be read.
std::string PairFileHash(const std::string& path);

/// The run a row must belong to.
struct RowExpectation {
    std::string pairs_hash;     ///< PairFileHash of the --pairs file
    std::size_t num_pairs = 0;  ///< pairs in that file
    int shard_index = 0;        ///< only pairs k with k % shard_count == shard_index
    int shard_count = 1;
    std::vector<MethodSpec> methods;  ///< names and resolved parameters
};

/// Checks one row (at `where` = "file:line"): every required field with the right type, a
/// known status, a pair of this file and shard, a listed method with the same resolved
/// parameters, the same pair-file hash. Throws std::runtime_error starting with `where`.
void CheckResultRow(const nlohmann::json& row,
                    const RowExpectation& expect,
                    const std::string& where);

/// Reads rows of an interrupted or finished run for --resume: each line is checked with
/// CheckResultRow and for duplicates (pair, method). Only an unterminated last line (a write
/// cut short by a kill) is dropped; any other unreadable line is an error with file:line.
std::vector<nlohmann::json> ReadResumableRows(const std::string& path,
                                              const RowExpectation& expect);

}  // namespace regbench
