#pragma once
// Experiment files: one table of the paper (experiments/plan/*.json, embedded into the binary)
// or of a user (`regbench reproduce --experiment FILE`) as data: the pair files to generate,
// the methods to run on them, the learned variants, and the table their rows fill. Every key
// is described in docs/reproducing.md, "Adding an experiment".
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "protocols/pair_protocols.hpp"

namespace regbench {

/// How many pairs an experiment gets from the run's count n (--pairs; else 10 with --quick,
/// else 1000): max(min, floor(scale * n)); `quick` replaces that with --quick and no --pairs;
/// `count` replaces everything.
struct PairCount {
    double scale = 1.0;
    std::size_t min = 0;
    std::size_t quick = 0;  ///< 0: the rule
    std::size_t count = 0;  ///< 0: the rule
};

/// One pair file and its results: one column group of one table.
struct ExperimentSpec {
    std::string id;     ///< file stem of its pairs and results, unique in a run
    std::string group;  ///< column group ("" for none)
    std::string protocol;
    std::string split;
    std::string dataset;  ///< name or path, as `regbench generate --dataset`
    /// "modelnet40", "7scenes" or "icl-nuim": the command-line root of that name replaces
    /// `dataset` when given (then a full run uses one pair per item of the split).
    std::string root;
    std::string fallback_note;  ///< caption note when `dataset` stands in for the root
    std::string pairing;        ///< "" = the protocol's default
    std::string root_pairing;   ///< pairing when the root is given ("" = `pairing`)
    bool noise_free = false;
    std::uint64_t seed_offset = 0;  ///< added to the run's --seed
    PairCount pairs;
    /// Non-empty: pair k belongs to group sweep[k % size] (the overlap-sweep protocol's levels).
    std::vector<std::string> sweep;
    /// Protocol parameters over the protocol's defaults, as in a pair file's provenance
    /// (e.g. {"sweep_keeps": [0.45]}: the overlap sweep's 50% level alone); checked on reading.
    nlohmann::json protocol_options = nlohmann::json::object();
    std::string comment;  ///< free text, ignored
};

/// One learned variant: a paper row and the config overrides it trains with.
struct Variant {
    std::string row;
    nlohmann::json config = nlohmann::json::object();
};

/// Learned variants (ablation rows): `regbench train --ablation KIND` trains each over `model`
/// into OUT/ROW; `reproduce` runs those shipped in data/models/ablation/KIND/ROW as `method`
/// on the pairs of experiment `pairs_of` ("" = none runs them). Absent: no rows.
struct VariantSpec {
    std::string kind;
    std::string method;
    std::string model;
    std::string pairs_of;
    std::vector<Variant> rows;
    /// true: each variant fills the column group named by its row, as `method`'s row (a sweep
    /// over variants: the cluster-count table); false: each is a row of its own.
    bool rows_are_groups = false;
    std::string comment;
};

/// One extra row of a timing table (Tab. 6): `method` with `params` (merged over its
/// defaults) on the pairs of the file's `timing_of`, shown as row `row` (the paper's row name,
/// e.g. "OGMM_full_attention": `ogmm` with {"attention": "full"}).
struct TimingVariant {
    std::string row;
    std::string method;
    nlohmann::json params = nlohmann::json::object();
    std::string comment;
};

struct ExperimentFile {
    std::string file;   ///< where it came from, for messages
    std::string table;  ///< table id; a key of the paper's tables puts its numbers beside ours
    std::string title;
    std::string caption;               ///< first sentence of the caption ("" = the paper's)
    std::vector<std::string> methods;  ///< empty: the run's methods
    std::vector<std::string> learned;  ///< rows say "not trained" when these cannot run
    std::vector<std::string> metrics;  ///< empty: mae_r, mae_t, ccd
    std::vector<ExperimentSpec> experiments;
    VariantSpec variants;
    std::string timing_of;  ///< a timing table (Tab. 6) of this experiment's rows
    std::vector<TimingVariant> timing_variants;  ///< its extra rows (needs timing_of)
    std::string comment;
};

/// Parses and checks one file's JSON (core/params.hpp's ParseConfig: unknown keys and wrong
/// types are refused); throws std::invalid_argument "experiment file FILE[: experiments[i]]:
/// parameter 'KEY' ..." naming the file and the key.
ExperimentFile ParseExperimentFile(const nlohmann::json& j, const std::string& file);

/// The protocol parameters experiment `s` generates its pairs with: the protocol's defaults,
/// then `protocol_options`, `pairing` and `noise_free`. Throws std::invalid_argument on an
/// unknown key or a bad value (ValidateProtocolOptions).
ProtocolOptions ProtocolOptionsOf(const ExperimentSpec& s);

/// Reads, parses and checks a file; throws naming the file.
ExperimentFile ReadExperimentFile(const std::string& path);

/// Checks a run's files together: unique table and experiment ids, and every experiment
/// named by `pairs_of` / `timing_of` among them.
void CheckExperimentFiles(const std::vector<ExperimentFile>& files);

/// The paper's plan: experiments/plan/*.json in name order, embedded at build time.
const std::vector<ExperimentFile>& PaperPlan();

/// A file embedded into the binary (cmake/EmbedPlan.cmake writes the list).
struct EmbeddedFile {
    const char* name;
    const char* text;
};
const std::vector<EmbeddedFile>& EmbeddedPlanFiles();

}  // namespace regbench
