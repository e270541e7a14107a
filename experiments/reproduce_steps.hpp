#pragma once
// The steps of one `regbench reproduce` shared by several machines or a Slurm array
// (docs/cluster.md, "The paper's tables on a cluster"), each invoked with the same options:
//   --prepare    generates every pair file into OUT/pairs once and records the plan's options
//                in OUT/shards/plan.json (before the array: the pairs are generated exactly once);
//   --shard i/n  runs shard i of n (pairs k with k % n == i) of every result file's calls into
//                OUT/shards/<i>-of-<n>/, resumable like any run (a rerun continues its shard);
//                shards run concurrently, each under its own lock;
//   --render     merges the shards of every result file into OUT/results/ (runners/merge: every
//                (experiment, pair, method) exactly once, or an error naming the rows) and
//                writes the reports as a one-machine run does.
// reproduce.cpp calls these at four places; a one-machine run (ReproduceOptions::Step::kAll)
// goes through them unchanged.
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "experiments/reproduce.hpp"
#include "runners/result_row.hpp"
#include "runners/run_options.hpp"

namespace regbench {

/// The folder this step locks: the report folder, or for --shard its own shard folder
/// (OUT/shards/<i>-of-<n>; OUT/shards is created here) so that shards run side by side.
std::string StepLockFolder(const ReproduceOptions& o, const std::string& folder);

/// Before any work. --prepare: refuses a folder prepared with other options. --shard and
/// --render: refuse a folder not prepared (no plan record, or a pair file missing: shards never
/// generate pairs) or prepared with other options, naming the option; --render also refuses
/// shard folders of several counts and a folder without any. `methods` by table, as reproduce
/// chose them (an experiment whose table has none is skipped and has no pair file).
void CheckStep(const ReproduceOptions& o, const std::vector<PlannedExperiment>& experiments,
               const std::map<std::string, std::vector<MethodSpec>>& methods,
               const std::string& out);

/// Where reproduce runs the calls of one result file (`run.out_path` = OUT/results/<stem>.jsonl)
/// and gets its rows, by step. All: runs it (resuming) and returns the file's rows. Prepare:
/// runs nothing, returns none. Shard: runs its shard into OUT/shards/<i>-of-<n>/<stem>.jsonl and
/// returns those rows. Render: merges the shards' files into run.out_path and returns its rows;
/// a merge that fails (rows missing or doubled, a shard not finished) is recorded in
/// summary.incomplete and returns none. summary.rows_run counts the calls made.
std::vector<ResultRow> RunResultFile(const RunOptions& run, const ReproduceOptions& o,
                                     const std::string& out, ReproduceSummary& summary);

/// After every result file went through RunResultFile. Prepare: records the plan and says what
/// comes next; shard: says what it did. Both return true (no reports in these steps). Render:
/// throws std::runtime_error naming every result file of summary.incomplete and its rows, else
/// returns false, as the one-machine run does.
bool FinishStep(const ReproduceOptions& o, const std::string& out, ReproduceSummary& summary,
                std::ostream& log);

}  // namespace regbench
