#include "runners/merge.hpp"

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <map>
#include <stdexcept>
#include <utility>

#include "core/atomic_file.hpp"
#include "core/file_lock.hpp"
#include "protocols/pair_file.hpp"
#include "runners/result_row.hpp"
#include "runners/resume.hpp"

namespace regbench {
namespace {

using RowKey = std::pair<std::size_t, std::size_t>;  // (pair, method index)

struct Located {
    ResultRow row;
    std::string where;  ///< file:line
};

/// Adds the rows of one shard file to `rows`, every line checked; no torn line is forgiven
/// here: a shard that did not finish has no final file to merge.
void AddRows(const std::string& path, const RowExpectation& expect,
             const std::map<std::string, std::size_t>& method_index,
             std::map<RowKey, Located>* rows) {
    ForEachJsonlLine(
        path, TornLastLine::kRefuse, [&](const std::string& where, const nlohmann::json& row) {
            ResultRow typed = CheckResultRow(row, expect, where);
            // Shards of one run score in one Euler convention; a mix would split the report.
            if (!rows->empty() && typed.euler != rows->begin()->second.row.euler) {
                const Located& first = rows->begin()->second;
                throw std::runtime_error(where + ": row scored with --euler " +
                                         ToString(typed.euler) + " but " + first.where +
                                         " with --euler " + ToString(first.row.euler));
            }
            const RowKey key{typed.pair, method_index.at(typed.method)};
            const auto [it, inserted] = rows->emplace(key, Located{std::move(typed), where});
            if (!inserted) {
                throw std::runtime_error(
                    where + ": duplicate row for pair " + std::to_string(key.first) + ", method '" +
                    expect.methods[key.second].name + "' (also at " + it->second.where + ")");
            }
        });
}

}  // namespace

std::size_t MergeResults(const MergeOptions& options) {
    if (options.inputs.empty()) throw std::invalid_argument("merge: no input files");
    if (options.methods.empty()) throw std::invalid_argument("merge: --methods is required");
    std::vector<std::string> inputs = options.inputs;
    inputs.push_back(options.pairs_path);
    CheckOutputPath(options.out_path, inputs);
    const OutputLock lock(options.out_path);
    RowExpectation expect;
    // The rows name their pairs by content hash, so the merge reads the pairs to recompute it
    // (DataTagOf also refuses a file modified since generation).
    const PairSet set = ReadPairFile(options.pairs_path);
    expect.num_pairs = set.pairs.size();
    expect.content_hash = DataTagOf(options.pairs_path, set).content_hash;
    // The methods' length parameters and the CCD clip as `run` set them for this pair file.
    expect.methods = PairScaledSpecs(options.methods, PairFileScale(options.pairs_path, set));
    expect.metric_options = PairMetricOptions(options.pairs_path, set, {}, false);
    std::map<std::string, std::size_t> method_index;
    for (std::size_t m = 0; m < options.methods.size(); ++m) {
        method_index[options.methods[m].name] = m;
    }
    std::map<RowKey, Located> rows;
    for (const auto& path : options.inputs) AddRows(path, expect, method_index, &rows);

    // Completeness: every pair of the file times every method, named when missing.
    std::string missing;
    std::size_t missing_count = 0;
    for (std::size_t k = 0; k < expect.num_pairs; ++k) {
        for (std::size_t m = 0; m < options.methods.size(); ++m) {
            if (rows.count({k, m})) continue;
            if (++missing_count <= 10) {
                missing += (missing.empty() ? "" : ", ") + std::string("pair ") +
                           std::to_string(k) + " " + options.methods[m].name;
            }
        }
    }
    if (missing_count > 0) {
        throw std::runtime_error(
            options.out_path + ": merge is incomplete: " + std::to_string(missing_count) + " of " +
            std::to_string(expect.num_pairs * options.methods.size()) + " rows missing (" +
            missing + (missing_count > 10 ? ", ..." : "") + ")");
    }
    std::vector<ResultRow> sorted;  // the map is ordered by (pair, method order)
    sorted.reserve(rows.size());
    for (auto& [key, located] : rows) sorted.push_back(std::move(located.row));
    WriteResultRows(options.out_path, sorted, inputs);
    return rows.size();
}

}  // namespace regbench
