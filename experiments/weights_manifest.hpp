#pragma once
// Which weights each learned method runs in each experiment of `regbench reproduce`: the
// weights manifest (`reproduce --weights FILE`, docs/reproducing.md "Reproducing with the
// authors' weights"). An entry names experiments (ids, or table ids for all of a table's),
// learned methods, and either a regbench checkpoint folder or an authors' .pth with its family
// and import settings, which is imported into the report folder before any pair is run.
// Entries apply in file order, a later one overriding an earlier one for the same
// (experiment, method); a learned method no entry names runs its shipped checkpoint.
// The shipped manifest (data/models/weights.json) is the default.
#include <map>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

namespace regbench {

struct WeightsEntry {
    std::string where;                     ///< "FILE: entry N (label)" for messages
    std::vector<std::string> experiments;  ///< experiment or table ids
    std::vector<std::string> methods;      ///< learned method names
    std::string label;                     ///< optional name of these weights in captions
    std::string checkpoint;                ///< a regbench checkpoint folder, or
    std::string authors_file;              ///< an authors' .pth, with
    std::string from;                      ///< its family (import-checkpoint --from)
    std::string preset;                    ///< --preset
    nlohmann::json settings = nlohmann::json::object();  ///< --setting KEY=VALUE
};

struct WeightsManifest {
    std::string path;  ///< "" = no manifest: every learned method runs its shipped checkpoint
    std::vector<WeightsEntry> entries;
};

/// Reads and checks a manifest's form: unknown keys, a missing or doubled checkpoint source,
/// wrong types are refused (std::invalid_argument naming the file and entry). Relative paths
/// resolve against the manifest's folder. Files and names are checked by ResolveWeights.
WeightsManifest ReadWeightsManifest(const std::string& path);

/// The shipped manifest: ShippedCheckpointDir("weights.json") (so $REGBENCH_MODELS moves it),
/// "" when that file does not exist.
std::string DefaultWeightsManifestPath();


/// One learned method's weights in one experiment.
struct WeightsChoice {
    std::string checkpoint;  ///< the folder it runs
    std::string label;       ///< the entry's label, else the checkpoint's
    std::string sha256;      ///< of the folder's weights file
    std::string source;      ///< shipped | authors | trained
    bool is_default = true;  ///< the method's own shipped folder (no checkpoint param needed)
    std::string Describe() const;
};

/// experiment id -> learned method -> weights.
using WeightsPlan = std::map<std::string, std::map<std::string, WeightsChoice>>;

/// What an experiment can run: its id, its table's id and the methods its table runs.
struct WeightsTarget {
    std::string experiment;
    std::string table;
    std::vector<std::string> methods;
};

/// `manifest` with only the experiment and table ids `targets` have, and without the entries
/// left with none: the shipped manifest names the paper's experiments, which a run of the
/// user's own experiment files does not have (a user's manifest is checked whole instead).
WeightsManifest OnlyTargetsOf(WeightsManifest manifest, const std::vector<WeightsTarget>& targets);

/// Checks every entry against the plan before any work: experiments and tables that exist,
/// methods that are learned and that the entry's tables run, checkpoint folders that exist,
/// authors' files that exist with a known family (refused naming the entry). Then imports each
/// authors' file once into `import_dir`/<entry> (kept when an earlier invocation imported the
/// same file with the same settings) and describes every learned method's weights in every
/// target. With `may_import` false (a shared run's shards), an authors' file not imported yet
/// is refused, naming the step that imports it. Without LibTorch: an empty plan, and an entry
/// is refused.
WeightsPlan ResolveWeights(const WeightsManifest& manifest,
                           const std::vector<WeightsTarget>& targets, const std::string& import_dir,
                           std::ostream& log, bool may_import = true);

/// The plan as JSON (written to OUT/weights.json) and the refusal of a resumed folder whose
/// recorded plan differs, naming the first difference.
nlohmann::json WeightsPlanJson(const WeightsManifest& manifest, const WeightsPlan& plan);
void CheckSameWeights(const nlohmann::json& recorded, const nlohmann::json& now,
                      const std::string& where);

}  // namespace regbench
