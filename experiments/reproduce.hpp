#pragma once
// `regbench reproduce`: the executor of experiment files (experiments/experiment_file.hpp).
// Generates their pairs, runs the methods on them (isolated, resumable, through runners/) and
// hands the rows to reports/, which renders every report into one folder.
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "experiments/experiment_file.hpp"

namespace regbench {

struct ReproduceOptions {
    /// A smoke run of every table: 10 pairs per experiment (5 per indoor set, 2 per overlap
    /// level) and the learned methods without their "-noicp" variants.
    bool quick = false;
    std::vector<std::string> tables;  ///< table ids or prefixes ("table1", "supp"); empty: all
    /// Experiment files run instead of the paper's plan (experiments/plan, embedded).
    std::vector<std::string> experiment_files;
    std::string modelnet40;   ///< ModelNet40 root (OFF tree or HDF5); empty: fallback
    std::string sevenscenes;  ///< 7Scenes root; empty: simulated indoor scans
    std::string icl_nuim;     ///< ICL-NUIM root; empty: simulated indoor scans
    std::string out_dir = "out/reproduce";
    std::string data_dir;            ///< where the embedded corpus lives (default: ./data)
    int jobs = 1;                    ///< pairs in parallel
    double timeout_seconds = 120.0;  ///< per call, in a child process (0: in-process)
    /// Pairs per experiment; 0: 10 with --quick, else 1000 on the fallbacks and one per item
    /// of the test split on real data.
    std::size_t pairs = 0;
    std::uint64_t seed = 1;            ///< benchmark seed of every pair file
    std::vector<std::string> methods;  ///< empty: every registered method that can be created
    bool progress = true;              ///< progress lines on stderr
    /// Weights manifest (experiments/weights_manifest.hpp): which checkpoint each learned
    /// method runs in each experiment; "" = the shipped one (data/models/weights.json).
    std::string weights;
    /// The run whole on one machine, or one step of it shared by several machines or a Slurm
    /// array (experiments/reproduce_steps.hpp, docs/cluster.md): generate the pairs, run one
    /// shard of every result file's calls, or merge the shards and write the reports.
    enum class Step { kAll, kPrepare, kShard, kRender };
    Step step = Step::kAll;
    int shard_index = 0;  ///< kShard: this shard, of
    int shard_count = 1;  ///< kShard: this many
};

struct ReproduceSummary {
    std::string out_dir;
    std::string html_path;
    std::string markdown_path;
    std::size_t experiments = 0;
    std::size_t pairs_generated = 0;  ///< pair files written by this invocation
    std::size_t rows_run = 0;         ///< method calls made by this invocation (resume skips)
    std::string shard_dir;            ///< kShard: the folder of this shard's results
    /// kRender: the result files whose shards did not merge, each with the rows named.
    std::vector<std::string> incomplete;
};

struct Provenance;

/// Provenance of a pair file as written by `regbench generate` (dataset, split, protocol,
/// pairing, seed, points, keep, version, content hash) plus its ground-truth CCD floor.
Provenance ProvenanceOfPairFile(const std::string& path);

/// One experiment of an experiment file, resolved for a run: one pair file and its results,
/// filling one column group of one table.
struct PlannedExperiment {
    ExperimentSpec spec;
    std::string table;     ///< the table of its file
    std::string dataset;   ///< the command-line root of spec.root when given, else spec.dataset
    std::string fallback;  ///< non-empty when standing in for the root's dataset
    std::string pairing;   ///< "" = the protocol's default (independent)
    std::size_t pairs = 0;
    std::uint64_t seed = 1;
    bool one_per_item = false;  ///< one pair per item of the split (`generate --pairs all`)
};

/// The experiments of the wanted tables (--tables) in file order, and those that wanted
/// tables use from other files (`timing_of`, `variants.pairs_of`), resolved for the options.
std::vector<PlannedExperiment> PlanExperiments(const std::vector<ExperimentFile>& files,
                                               const ReproduceOptions& o);

/// Table ids of the paper's plan (paper order).
std::vector<std::string> ReproducibleTables();

/// Runs everything; progress and decisions go to `log`. Throws std::runtime_error naming the
/// input on bad options or data.
ReproduceSummary Reproduce(const ReproduceOptions& options, std::ostream& log);

}  // namespace regbench
