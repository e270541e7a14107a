#include "experiments/reproduce_steps.hpp"

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <stdexcept>

#include "core/atomic_file.hpp"
#include "runners/merge.hpp"
#include "runners/runner.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;
using Step = ReproduceOptions::Step;

fs::path ShardsDir(const fs::path& out) { return out / "shards"; }
fs::path PlanRecordPath(const fs::path& out) { return ShardsDir(out) / "plan.json"; }

std::string ShardName(int index, int count) {
    return std::to_string(index) + "-of-" + std::to_string(count);
}

const char* StepFlag(Step step) {
    switch (step) {
        case Step::kPrepare:
            return "--prepare";
        case Step::kShard:
            return "--shard";
        case Step::kRender:
            return "--render";
        case Step::kAll:
            break;
    }
    return "";
}

/// The options that decide which calls a run makes and what its rows hold, keyed by their
/// flags: every step of one run must be given the same (not --jobs, --data-dir, --out).
nlohmann::json PlanRecord(const ReproduceOptions& o) {
    return {{"--quick", o.quick},
            {"--tables", o.tables},
            {"--experiment", o.experiment_files},
            {"--modelnet40", o.modelnet40},
            {"--7scenes", o.sevenscenes},
            {"--icl-nuim", o.icl_nuim},
            {"--pairs", o.pairs},
            {"--seed", o.seed},
            {"--methods", o.methods},
            {"--timeout", o.timeout_seconds}};
}

/// Refuses options that differ from those the folder was prepared with, naming the first.
void CheckPlanRecord(const ReproduceOptions& o, const fs::path& out) {
    const fs::path path = PlanRecordPath(out);
    nlohmann::json recorded;
    try {
        std::ifstream in(path);
        recorded = nlohmann::json::parse(in);
    } catch (const std::exception& e) {
        throw std::runtime_error(
            path.string() + ": cannot read the plan record (" + e.what() +
            "); run `regbench reproduce --prepare` again with the run's options");
    }
    const nlohmann::json mine = PlanRecord(o);
    for (const auto& item : mine.items()) {
        const nlohmann::json was = recorded.value(item.key(), nlohmann::json());
        if (was != item.value()) {
            throw std::runtime_error(
                path.string() + ": this folder was prepared with " + item.key() + " " + was.dump() +
                ", this " + StepFlag(o.step) + " step has " + item.value().dump() +
                ": give every step of a run the same options (or prepare a new folder)");
        }
    }
}

/// The shard count of OUT/shards/<i>-of-<n>/ folders and their paths for i = 0..n-1 (those
/// that never ran included: their rows are missing). Throws when there is none, or when
/// folders of several counts are there (which set is meant is not for render to guess).
std::pair<int, std::vector<fs::path>> ShardFolders(const fs::path& out) {
    static const std::regex name(R"(([0-9]{1,9})-of-([0-9]{1,9}))");
    std::map<int, std::vector<std::string>> by_count;
    if (fs::is_directory(ShardsDir(out))) {
        for (const auto& entry : fs::directory_iterator(ShardsDir(out))) {
            std::smatch m;
            const std::string base = entry.path().filename().string();
            if (!entry.is_directory() || !std::regex_match(base, m, name)) continue;
            const int i = std::stoi(m[1]);
            const int n = std::stoi(m[2]);
            if (n >= 1 && i < n) by_count[n].push_back(base);
        }
    }
    if (by_count.empty()) {
        throw std::runtime_error(ShardsDir(out).string() +
                                 ": no shard results (<i>-of-<n>/): run `regbench reproduce "
                                 "--shard i/n` for i = 0..n-1 before --render");
    }
    if (by_count.size() > 1) {
        std::string sets;
        for (const auto& [n, names] : by_count) {
            sets += (sets.empty() ? "" : "; ") + std::to_string(n) + " shards (" + names.front() +
                    (names.size() > 1 ? ", ..." : "") + ")";
        }
        throw std::runtime_error(ShardsDir(out).string() + " holds shards of several counts: " +
                                 sets + ": remove the folders of the set not to be merged");
    }
    const int n = by_count.begin()->first;
    std::vector<fs::path> folders;
    for (int i = 0; i < n; ++i) folders.push_back(ShardsDir(out) / ShardName(i, n));
    return {n, folders};
}

/// Render: the shards' files of one result file merged into run.out_path.
std::vector<ResultRow> MergeShards(const RunOptions& run, const fs::path& out,
                                   ReproduceSummary& summary) {
    const std::string file = fs::path(run.out_path).filename().string();
    const std::string stem = file.substr(0, file.size() - std::string(".jsonl").size());
    std::vector<std::string> inputs;
    std::string unfinished;
    for (const fs::path& folder : ShardFolders(out).second) {
        const fs::path shard = folder / file;
        if (fs::exists(shard)) {
            inputs.push_back(shard.string());
            continue;
        }
        unfinished += (unfinished.empty() ? "" : ", ") + folder.filename().string() +
                      (!fs::exists(folder)                    ? " never ran"
                       : fs::exists(shard.string() + ".part") ? " stopped part-way"
                                                              : " did not reach it");
    }
    const std::string note = unfinished.empty() ? "" : " [shards: " + unfinished + "]";
    if (inputs.empty()) {
        summary.incomplete.push_back(stem + ": no shard finished it, every row is missing" + note);
        return {};
    }
    try {
        MergeOptions merge;
        merge.inputs = inputs;
        merge.out_path = run.out_path;
        merge.pairs_path = run.pairs_path;
        merge.methods = run.methods;
        MergeResults(merge);
    } catch (const std::exception& e) {
        summary.incomplete.push_back(stem + ": " + e.what() + note);
        return {};
    }
    return ReadResultRows(run.out_path);
}

}  // namespace

std::string StepLockFolder(const ReproduceOptions& o, const std::string& folder) {
    if (o.step != Step::kShard) return folder;
    if (o.shard_count < 1 || o.shard_index < 0 || o.shard_index >= o.shard_count) {
        throw std::invalid_argument("--shard must be i/n with 0 <= i < n");
    }
    // The folder itself appears with the shard's first results (RunResultFile), so a shard
    // refused before any work leaves nothing a render would count.
    fs::create_directories(ShardsDir(folder));
    return (ShardsDir(folder) / ShardName(o.shard_index, o.shard_count)).string();
}

void CheckStep(const ReproduceOptions& o, const std::vector<PlannedExperiment>& experiments,
               const std::map<std::string, std::vector<MethodSpec>>& methods,
               const std::string& out_dir) {
    const fs::path out(out_dir);
    if (o.step == Step::kAll) return;
    if (o.step == Step::kPrepare) {
        if (fs::exists(PlanRecordPath(out))) CheckPlanRecord(o, out);
        return;
    }
    if (!fs::exists(PlanRecordPath(out))) {
        throw std::runtime_error(out.string() + " is not prepared for shards (no " +
                                 PlanRecordPath(out).string() +
                                 "): run `regbench reproduce --prepare` with the same options "
                                 "first, once, before the shards");
    }
    CheckPlanRecord(o, out);
    for (const auto& e : experiments) {
        if (methods.at(e.table).empty()) continue;  // skipped by the run: no pair file
        const fs::path pairs = out / "pairs" / (e.spec.id + ".h5");
        if (!fs::exists(pairs)) {
            throw std::runtime_error(pairs.string() +
                                     ": missing, though the folder was prepared; shards never "
                                     "generate pairs: run `regbench reproduce --prepare` again");
        }
    }
    if (o.step == Step::kRender) ShardFolders(out);  // refuses none, or several counts
}

std::vector<ResultRow> RunResultFile(const RunOptions& run, const ReproduceOptions& o,
                                     const std::string& out, ReproduceSummary& summary) {
    switch (o.step) {
        case Step::kPrepare:
            return {};
        case Step::kShard: {
            RunOptions shard = run;
            shard.shard_index = o.shard_index;
            shard.shard_count = o.shard_count;
            const fs::path folder = ShardsDir(out) / ShardName(o.shard_index, o.shard_count);
            shard.out_path = (folder / fs::path(run.out_path).filename()).string();
            fs::create_directories(folder);
            summary.shard_dir = folder.string();
            summary.rows_run += RunBenchmark(shard).rows_written;
            return ReadResultRows(shard.out_path);
        }
        case Step::kRender:
            return MergeShards(run, out, summary);
        case Step::kAll:
            break;
    }
    summary.rows_run += RunBenchmark(run).rows_written;
    return ReadResultRows(run.out_path);
}

bool FinishStep(const ReproduceOptions& o, const std::string& out_dir, ReproduceSummary& summary,
                std::ostream& log) {
    const fs::path out(out_dir);
    switch (o.step) {
        case Step::kAll:
            return false;
        case Step::kPrepare:
            if (!fs::exists(PlanRecordPath(out))) {
                fs::create_directories(ShardsDir(out));
                WriteFileAtomic(PlanRecordPath(out).string(), PlanRecord(o).dump(1) + "\n");
            }
            log << "reproduce --prepare: " << summary.pairs_generated
                << " pair files generated into " << (out / "pairs").string()
                << ", the plan recorded in " << PlanRecordPath(out).string()
                << "; next: reproduce --shard i/n for i = 0..n-1 (same options), then "
                   "reproduce --render\n";
            return true;
        case Step::kShard:
            log << "reproduce --shard " << o.shard_index << "/" << o.shard_count << ": "
                << summary.rows_run << " calls run into " << summary.shard_dir
                << "; reproduce --render once every shard has finished\n";
            return true;
        case Step::kRender:
            break;
    }
    if (summary.incomplete.empty()) return false;
    std::string what = "reproduce --render: " + std::to_string(summary.incomplete.size()) +
                       " result file(s) do not merge, no report written:";
    for (const auto& line : summary.incomplete) what += "\n  " + line;
    throw std::runtime_error(what);
}

}  // namespace regbench
