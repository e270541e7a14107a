#pragma once
// What an existing results file must satisfy before its rows are kept (--resume) or merged:
// rows from other pair data, other methods or parameters, duplicates or rows missing fields
// are refused with file:line, never mixed into a result.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "runners/result_row.hpp"
#include "runners/run_options.hpp"

namespace regbench {

/// The run a row must belong to.
struct RowExpectation {
    /// PairSetContentHash of the --pairs data; rows carry it in data.content_hash. It names the
    /// pairs, not the file's bytes, so a re-export of identical pairs still matches.
    std::string content_hash;
    std::size_t num_pairs = 0;  ///< pairs in that file
    int shard_index = 0;        ///< only pairs k with k % shard_count == shard_index
    int shard_count = 1;
    std::vector<MethodSpec> methods;  ///< names and resolved parameters
    MetricOptions metric_options;     ///< the CCD clip and inlier threshold of the metrics
};

/// Checks one row (at `where` = "file:line"): every required field with the right type, a
/// status a run writes (ok, failed, timeout, crashed), a pair of this file and shard, a listed
/// method with the same resolved parameters, the same pair content hash. Returns the typed row
/// (origin = where). Throws std::runtime_error starting with `where`.
ResultRow CheckResultRow(const nlohmann::json& row, const RowExpectation& expect,
                         const std::string& where);

/// Reads rows of an interrupted or finished run for --resume: each line is checked with
/// CheckResultRow and for duplicates (pair, method). Only an unterminated last line (a write
/// cut short by a kill) is dropped; any other unreadable line is an error with file:line.
std::vector<ResultRow> ReadResumableRows(const std::string& path, const RowExpectation& expect);

}  // namespace regbench
