#include "experiments/reproduce.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <ostream>
#include <set>
#include <stdexcept>
#include <utility>

#include "core/atomic_file.hpp"
#include "core/cpu_time.hpp"
#include "core/file_lock.hpp"
#include "core/json_limits.hpp"
#include "core/usage_error.hpp"
#include "core/version.hpp"
#include "datasets/dataset_shapes.hpp"
#include "experiments/experiment_file.hpp"
#include "experiments/reproduce_steps.hpp"
#include "experiments/weights_manifest.hpp"
#include "protocols/generate.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_hash.hpp"
#include "protocols/pair_summary.hpp"
#include "reports/breakdown.hpp"
#include "reports/curves.hpp"
#include "reports/html_report.hpp"
#include "reports/paper_report.hpp"
#include "reports/paper_tables.hpp"
#include "runners/registry.hpp"
#include "runners/runner.hpp"
#ifdef REGBENCH_HAVE_LEARNED
#include "baselines/learned.hpp"
#endif

namespace regbench {
namespace {

namespace fs = std::filesystem;

bool Wanted(const std::vector<std::string>& wanted, const std::string& table) {
    if (wanted.empty()) return true;
    for (const auto& w : wanted) {
        if (table.rfind(w, 0) == 0) return true;
    }
    return false;
}

/// The command-line root of `root` ("" when not given).
std::string RootPath(const std::string& root, const ReproduceOptions& o) {
    if (root == "modelnet40") return o.modelnet40;
    if (root == "7scenes") return o.sevenscenes;
    return root == "icl-nuim" ? o.icl_nuim : "";
}

/// The pair count of PairCount's rule for this run.
std::size_t PairsOf(const PairCount& c, const ReproduceOptions& o) {
    if (c.count > 0) return c.count;
    if (o.quick && o.pairs == 0 && c.quick > 0) return c.quick;
    const std::size_t n = o.pairs > 0 ? o.pairs : (o.quick ? 10 : 1000);
    return std::max(c.min, static_cast<std::size_t>(std::floor(c.scale * static_cast<double>(n))));
}

PlannedExperiment Resolve(const ExperimentSpec& s, const std::string& table,
                          const ReproduceOptions& o) {
    PlannedExperiment e;
    e.spec = s;
    e.table = table;
    const std::string root = s.root.empty() ? "" : RootPath(s.root, o);
    e.dataset = root.empty() ? s.dataset : root;
    e.fallback = root.empty() ? s.fallback_note : "";
    e.pairing = !root.empty() && !s.root_pairing.empty() ? s.root_pairing : s.pairing;
    e.pairs = PairsOf(s.pairs, o);
    e.seed = o.seed + s.seed_offset;
    // Full runs on real data use every test item once (as the authors evaluate), unless
    // --pairs or the file fixes the count; --quick and the fallbacks keep the count.
    e.one_per_item = !root.empty() && o.pairs == 0 && !o.quick && s.pairs.count == 0;
    return e;
}

}  // namespace

std::vector<PlannedExperiment> PlanExperiments(const std::vector<ExperimentFile>& files,
                                               const ReproduceOptions& o) {
    std::set<std::string> used;
    for (const auto& f : files) {
        if (!Wanted(o.tables, f.table)) continue;
        used.insert(f.timing_of);
        used.insert(f.variants.pairs_of);
    }
    std::vector<PlannedExperiment> out;
    for (const auto& f : files) {
        for (const auto& s : f.experiments) {
            if (!Wanted(o.tables, f.table) && !used.count(s.id)) continue;
            out.push_back(Resolve(s, f.table, o));
            // Refused before any work, by name: 0 pairs made `generate` fail mid-run.
            if (out.back().pairs == 0) {
                throw std::invalid_argument(
                    "experiment file " + f.file + ": experiment '" + s.id +
                    "' gets 0 pairs at this --pairs (max(min, floor(scale * n)) = 0): give "
                    "its \"pairs\" a \"min\" >= 1 or run with a larger --pairs");
            }
        }
    }
    return out;
}

namespace {

/// Writes `text` to `path` atomically and checked (core/atomic_file).
void WriteText(const fs::path& path, const std::string& text) {
    WriteFileAtomic(path.string(), text);
}

/// Methods to run: `names` (a file's or --methods; empty: every registered one), and the
/// reasons the wanted ones that cannot run are left out. Only methods in `learned` may be left
/// out of a list that names them; a file's list (no --methods given) may end up empty (its table
/// then says why), --methods may not.
std::vector<MethodSpec> ChooseMethods(std::vector<std::string> names,
                                      const std::set<std::string>& learned,
                                      const ReproduceOptions& o,
                                      std::map<std::string, std::string>* unavailable,
                                      std::ostream& log) {
    const bool named = !names.empty();
    if (!named) {
        for (const auto& m : AllMethods()) {
            // --quick leaves out the learned methods' "-noicp" variants: no paper row, and the
            // network calls dominate a quick run's time (docs/reports.md).
            const bool noicp = m.name.size() > 6 && m.name.substr(m.name.size() - 6) == "-noicp";
            if (o.quick && noicp) {
                log << "reproduce: --quick leaves out " << m.name
                    << " (no paper row; the full run includes it)\n";
                continue;
            }
            names.push_back(m.name);
        }
    }
    std::vector<MethodSpec> specs;
    for (const auto& name : names) {
        try {
            CreateMethod(name, nlohmann::json::object());  // checkpoints load here
            specs.push_back({name, FindMethod(name).defaults});
        } catch (const std::exception& e) {
            if (named && !learned.count(name)) throw;
            (*unavailable)[name] = "not trained";
            log << "reproduce: " << name << " left out (not trained: " << e.what() << ")\n";
        }
    }
    const bool from_file = o.methods.empty();
    if (specs.empty() && !(named && from_file)) {
        throw std::runtime_error("reproduce: no method can run");
    }
    return specs;
}

/// Each file's methods (ChooseMethods once per distinct list), by table id; learned methods
/// this build does not register are marked "not trained".
std::map<std::string, std::vector<MethodSpec>> ChooseAllMethods(
    const std::vector<ExperimentFile>& files, const ReproduceOptions& o,
    std::map<std::string, std::string>* unavailable, std::ostream& log) {
    std::set<std::string> learned;
    for (const auto& f : files) learned.insert(f.learned.begin(), f.learned.end());
    std::map<std::vector<std::string>, std::vector<MethodSpec>> by_list;
    std::map<std::string, std::vector<MethodSpec>> by_table;
    for (const auto& f : files) {
        const auto& names = o.methods.empty() ? f.methods : o.methods;
        if (!by_list.count(names))
            by_list[names] = ChooseMethods(names, learned, o, unavailable, log);
        by_table[f.table] = by_list[names];
    }
    for (const auto& name : learned) {
        bool registered = false;
        for (const auto& m : AllMethods()) registered |= m.name == name;
        if (!registered && !unavailable->count(name)) {
            (*unavailable)[name] = "not trained";
            log << "reproduce: " << name << " is not registered in this build: not trained\n";
        }
    }
    return by_table;
}

/// Generates the pair file unless a previous invocation did.
bool EnsurePairs(const PlannedExperiment& e, const fs::path& path, const ReproduceOptions& o,
                 std::ostream& log) {
    if (fs::exists(path)) return false;
    GenerateRequest request;
    const ExperimentSpec& s = e.spec;
    request.dataset = e.dataset;
    request.split = s.split;
    request.num_pairs = e.pairs;
    request.seed = e.seed;
    request.options = ProtocolOptionsOf(s);
    if (!e.pairing.empty()) request.options.pairing = ParsePairing(e.pairing);  // root_pairing
    request.one_per_item = e.one_per_item;
    request.out = path.string();
    request.extra_provenance = {{"regbench_version", RegbenchVersion()},
                                {"reproduce_experiment", s.id}};
    if (!e.fallback.empty()) request.extra_provenance["fallback"] = e.fallback;
    DatasetOptions dataset_options;
    dataset_options.data_dir = o.data_dir;
    log << fmt::format("reproduce: {}: generating {} {} pairs ({} pairing{}) from {} ({})\n", s.id,
                       e.one_per_item ? "one per item" : std::to_string(e.pairs), s.protocol,
                       e.pairing.empty() ? "independent" : e.pairing,
                       s.noise_free ? ", noise-free" : "", e.dataset, s.split);
    GenerateToFile(request, DatasetShapeLoader(dataset_options));
    return true;
}

/// Splits a sweep's rows into its levels (pair k has level k % levels).
std::vector<ResultSet> SweepSets(const std::vector<std::string>& levels,
                                 const std::vector<ResultRow>& rows, const Provenance& p) {
    std::vector<ResultSet> sets;
    for (std::size_t l = 0; l < levels.size(); ++l) {
        ResultSet s{levels[l], {}, p, ""};
        for (const auto& r : rows) {
            if (r.pair % levels.size() == l) s.rows.push_back(r);
        }
        sets.push_back(s);
    }
    return sets;
}

/// How `reproduce` runs methods on one pair file: its jobs, per-call timeout and progress,
/// resuming the finished rows of a previous invocation.
RunOptions ExperimentRun(const ReproduceOptions& o, const fs::path& pairs,
                         std::vector<MethodSpec> methods, const fs::path& results) {
    RunOptions run;
    run.pairs_path = pairs.string();
    run.methods = std::move(methods);
    run.out_path = results.string();
    run.jobs = o.jobs;
    run.resume = true;
    run.timeout_seconds = o.timeout_seconds;
    run.progress = o.progress;
    return run;
}

std::string Join(const std::vector<Table>& tables,
                 const std::function<std::string(const Table&)>& fn) {
    std::string s;
    for (const auto& t : tables) s += fn(t) + "\n";
    return s;
}

}  // namespace

Provenance ProvenanceOfPairFile(const std::string& path) {
    const PairSet set = ReadPairFile(path);
    const auto& pv = set.provenance;
    Provenance p;
    p.pairs_file =
        path.substr(path.find_last_of('/') == std::string::npos ? 0 : path.find_last_of('/') + 1);
    p.dataset = pv.value("dataset", std::string("unknown"));
    p.split = pv.value("split", std::string());
    p.protocol = pv.value("protocol", std::string("unknown"));
    const auto params = pv.value("params", nlohmann::json::object());
    p.pairing = pv.value("pairing", params.value("pairing", std::string()));
    p.seed = pv.value("seed", nlohmann::json());
    p.points = params.value("points", 0);
    p.keep = params.value("keep", 0.0);
    p.version = pv.value("regbench_version", std::string()) +
                (pv.contains("git_sha") ? "+" + pv["git_sha"].get<std::string>() : "");
    p.pairs_hash = PairSetContentHash(set);  // what the runner records in every row
    p.gt_ccd_floor = SummarizePairSet(set).gt_ccd_mean;
    p.selection = pv.value("pair_selection", std::string());
    if (pv.contains("noise_sigma") && pv["noise_sigma"].is_number()) {
        p.noise_sigma = pv["noise_sigma"].get<double>();
    }
    return p;
}

std::vector<std::string> ReproducibleTables() {
    std::vector<std::string> ids;
    for (const auto& f : PaperPlan()) ids.push_back(f.table);
    return ids;
}

namespace {

/// Refuses table names that match no table of `files` and dataset paths that do not exist,
/// before any work starts: a UsageError (exit 2), the command line being at fault.
void ValidateOptions(const ReproduceOptions& o, const std::vector<ExperimentFile>& files) {
    if (o.jobs < 1) throw UsageError("--jobs must be at least 1");
    if (!(o.timeout_seconds >= 0.0)) throw UsageError("--timeout must be >= 0");
    for (const auto& t : o.tables) {
        bool known = false;
        for (const auto& f : files) known |= f.table.rfind(t, 0) == 0;
        if (!known) {
            std::string list;
            for (const auto& f : files) list += (list.empty() ? "" : ", ") + f.table;
            throw UsageError("--tables: '" + t + "' names no table (" + list + ")");
        }
    }
    for (const auto& [flag, path] :
         {std::pair<const char*, std::string>{"--modelnet40", o.modelnet40},
          {"--7scenes", o.sevenscenes},
          {"--icl-nuim", o.icl_nuim}}) {
        if (!path.empty() && !fs::exists(path)) {
            throw UsageError(std::string(flag) + " " + path + ": no such file or folder");
        }
    }
}

/// `methods` with each learned method's checkpoint of experiment `id` (a checkpoint parameter
/// where it is not the method's shipped folder, so rows of the shipped weights stay as they
/// were), and in `note` the weights every learned method runs, for the captions.
std::vector<MethodSpec> WithWeights(std::vector<MethodSpec> methods, const WeightsPlan& weights,
                                    const std::string& id, std::string* note) {
    const auto it = weights.find(id);
    if (it == weights.end()) return methods;
    for (auto& spec : methods) {
        const auto c = it->second.find(spec.name);
        if (c == it->second.end()) continue;
        if (!c->second.is_default) spec.params["checkpoint"] = c->second.checkpoint;
        *note += (note->empty() ? "" : "; ") + spec.name + " = " + c->second.Describe();
    }
    return methods;
}

/// The weights manifest's plan for this run (refused before any work when an entry does not
/// fit), recorded in OUT/weights.json; a folder run with other weights is refused. A shared
/// run's --prepare imports the authors' files and writes the record; --shard and --render
/// only check against it (they run at the same time and must not write it).
WeightsPlan PlanWeights(const std::vector<ExperimentFile>& files, const ReproduceOptions& o,
                        const fs::path& out, std::ostream& log) {
    const std::string path = o.weights.empty() ? DefaultWeightsManifestPath() : o.weights;
    WeightsManifest manifest = path.empty() ? WeightsManifest{} : ReadWeightsManifest(path);
    // Every experiment of the files, not only those of --tables: a manifest of the whole
    // paper fits a run of one table, and the record does not change with --tables.
    std::vector<WeightsTarget> targets;
    for (const auto& f : files) {
        std::vector<std::string> names = f.methods;
        if (names.empty()) {
            for (const auto& m : AllMethods()) names.push_back(m.name);
        }
        for (const auto& e : f.experiments) targets.push_back({e.id, f.table, names});
    }
    // The shipped manifest names the paper's experiments; a run of other experiment files
    // keeps what applies to it. A manifest the user gives must fit whole.
    if (o.weights.empty()) manifest = OnlyTargetsOf(manifest, targets);
    const bool shared_step =
        o.step == ReproduceOptions::Step::kShard || o.step == ReproduceOptions::Step::kRender;
    const WeightsPlan plan =
        ResolveWeights(manifest, targets, (out / "weights").string(), log, !shared_step);
    const nlohmann::json now = WeightsPlanJson(manifest, plan);
    const fs::path record = out / "weights.json";
    if (fs::exists(record)) {
        CheckSameWeights(ReadJsonFileBounded(record.string(), record.string()), now,
                         "reproduce: " + out.string());
    }
    if (!shared_step) {
        fs::create_directories(out);
        WriteText(record, now.dump(1) + "\n");
    }
    if (!manifest.path.empty()) log << "reproduce: weights from " << manifest.path << "\n";
    return plan;
}

/// Each experiment's result rows, pair-file provenance and pairs, by experiment id.
struct ExperimentOutputs {
    std::map<std::string, std::vector<ResultRow>> rows;
    std::map<std::string, Provenance> provenance;
    std::map<std::string, PairSet> pairs;
};

/// Generates and runs every experiment; each step is skipped or resumed when done before.
ExperimentOutputs RunExperiments(const std::vector<PlannedExperiment>& experiments,
                                 const std::map<std::string, std::vector<MethodSpec>>& methods,
                                 const WeightsPlan& weights, const ReproduceOptions& o,
                                 const fs::path& out, ReproduceSummary& summary,
                                 std::ostream& log) {
    ExperimentOutputs x;
    for (const auto& e : experiments) {
        const std::string& id = e.spec.id;
        const fs::path pairs = out / "pairs" / (id + ".h5");
        const fs::path results = out / "results" / (id + ".jsonl");
        std::string weights_note;
        const auto m = WithWeights(methods.at(e.table), weights, id, &weights_note);
        if (m.empty()) {  // a file naming only learned methods, none trained in this build
            log << "reproduce: " << id << ": none of its methods can run, skipped\n";
            continue;
        }
        summary.pairs_generated += EnsurePairs(e, pairs, o, log) ? 1 : 0;
        const RunOptions run = ExperimentRun(o, pairs, m, results);
        log << "reproduce: " << id << ": running " << m.size() << " methods\n";
        x.rows[id] = RunResultFile(run, o, out.string(), summary);  // by step (reproduce_steps)
        x.provenance[id] = ProvenanceOfPairFile(pairs.string());
        x.provenance[id].fallback = e.fallback;
        x.provenance[id].weights = weights_note;
        x.pairs[id] = ReadPairFile(pairs.string());
    }
    return x;
}

/// Learned variants (the ablations, Tab. 4, 5): every variant with a shipped checkpoint
/// (data/models/ablation/<kind>/<row>, written by `regbench train --ablation`) runs as its
/// method on the pairs of its `pairs_of` experiment; variants without one say "not trained"
/// (in BuildTables). Returns the variants' result sets by table id.
std::map<std::string, std::vector<ResultSet>> RunVariants(
    [[maybe_unused]] const std::vector<ExperimentFile>& files,
    [[maybe_unused]] const std::map<std::string, std::vector<MethodSpec>>& methods,
    [[maybe_unused]] const ExperimentOutputs& x, [[maybe_unused]] const ReproduceOptions& o,
    [[maybe_unused]] const fs::path& out, [[maybe_unused]] ReproduceSummary& summary,
    [[maybe_unused]] std::ostream& log) {
    std::map<std::string, std::vector<ResultSet>> variant_sets;
#ifdef REGBENCH_HAVE_LEARNED
    for (const auto& f : files) {
        if (!Wanted(o.tables, f.table) || !x.rows.count(f.variants.pairs_of)) continue;
        const VariantSpec& v = f.variants;
        const auto& m = methods.at(f.table);
        if (std::none_of(m.begin(), m.end(),
                         [&](const MethodSpec& s) { return s.name == v.method; })) {
            log << "reproduce: " << f.table << ": " << v.method
                << " cannot run, its variants are not run\n";
            continue;
        }
        // In row-name order, as before the plan was data (the paper JSON's rows, a sorted map).
        std::vector<Variant> rows = v.rows;
        std::sort(rows.begin(), rows.end(),
                  [](const auto& a, const auto& b) { return a.row < b.row; });
        for (const auto& row : rows) {
            const std::string dir = ShippedCheckpointDir("ablation/" + v.kind + "/" + row.row);
            if (!fs::exists(fs::path(dir) / "checkpoint.json")) continue;
            MethodSpec spec{v.method, FindMethod(v.method).defaults};
            spec.params["checkpoint"] = dir;
            std::string stem = "ablation_" + v.kind + "_" + row.row;
            std::replace(stem.begin(), stem.end(), '+', '_');
            const RunOptions run = ExperimentRun(o, out / "pairs" / (v.pairs_of + ".h5"), {spec},
                                                 out / "results" / (stem + ".jsonl"));
            log << "reproduce: " << f.table << ": variant " << row.row << " (checkpoint " << dir
                << ")\n";
            variant_sets[f.table].push_back(
                {v.rows_are_groups ? row.row : "", RunResultFile(run, o, out.string(), summary),
                 x.provenance.at(v.pairs_of), v.rows_are_groups ? "" : row.row});
        }
    }
#endif
    return variant_sets;
}

/// The extra rows of the timing tables (Tab. 6's OGMM_full_attention): each timing variant's
/// method, with its params over the defaults, on the pairs of the file's `timing_of`, into
/// results/timing_<row>.jsonl; left out (logged) when its method does not run in this
/// invocation. Returns the variants' result sets, labelled with their rows, by table id.
std::map<std::string, std::vector<ResultSet>> RunTimingVariants(
    const std::vector<ExperimentFile>& files,
    const std::map<std::string, std::vector<MethodSpec>>& methods, const ExperimentOutputs& x,
    const ReproduceOptions& o, const fs::path& out, ReproduceSummary& summary, std::ostream& log) {
    std::map<std::string, std::vector<ResultSet>> sets;
    for (const auto& f : files) {
        if (!Wanted(o.tables, f.table) || !x.rows.count(f.timing_of)) continue;
        const auto& m = methods.at(f.table);
        for (const auto& v : f.timing_variants) {
            if (std::none_of(m.begin(), m.end(),
                             [&](const MethodSpec& s) { return s.name == v.method; })) {
                log << "reproduce: " << f.table << ": " << v.method << " does not run, so row "
                    << v.row << " is not run\n";
                continue;
            }
            MethodSpec spec{v.method, FindMethod(v.method).defaults};
            spec.params.merge_patch(v.params);
            std::string stem = "timing_" + v.row;
            std::replace_if(
                stem.begin(), stem.end(),
                [](char c) { return !std::isalnum(static_cast<unsigned char>(c)) && c != '-'; },
                '_');
            const RunOptions run = ExperimentRun(o, out / "pairs" / (f.timing_of + ".h5"), {spec},
                                                 out / "results" / (stem + ".jsonl"));
            log << "reproduce: " << f.table << ": row " << v.row << " (" << v.method << " "
                << v.params.dump() << ")\n";
            sets[f.table].push_back({"", RunResultFile(run, o, out.string(), summary),
                                     x.provenance.at(f.timing_of), v.row});
        }
    }
    return sets;
}

/// The table of a file: the paper's spec of its id, or (a table the paper lacks) one whose
/// column groups are its experiments'; the file's title, caption and metrics win.
PaperTableSpec SpecOf(const ExperimentFile& f) {
    PaperTableSpec spec;
    spec.metrics = {"mae_r", "mae_t", "ccd"};
    const auto& paper = PaperTableSpecs();
    const auto it = std::find_if(paper.begin(), paper.end(),
                                 [&](const PaperTableSpec& s) { return s.id == f.table; });
    if (it != paper.end()) spec = *it;
    spec.id = f.table;
    spec.title = f.title;
    if (!f.caption.empty()) spec.caption = f.caption;
    if (!f.metrics.empty()) spec.metrics = f.metrics;
    if (it == paper.end()) {
        for (const auto& e : f.experiments) {
            for (const auto& g : e.sweep.empty() ? std::vector<std::string>{e.group} : e.sweep) {
                if (std::find(spec.groups.begin(), spec.groups.end(), g) == spec.groups.end())
                    spec.groups.push_back(g);
            }
        }
    }
    return spec;
}

/// The result sets of a file's table: its experiments' rows (a sweep's split into its
/// levels), then its variants', with every unmeasured variant row of the paper marked.
std::vector<ResultSet> SetsOf(const ExperimentFile& f, const PaperTableSpec& spec,
                              const std::vector<PlannedExperiment>& experiments,
                              ExperimentOutputs& x,
                              std::map<std::string, std::vector<ResultSet>>& variant_sets,
                              const nlohmann::json& paper, PaperTableOptions* to) {
    std::vector<ResultSet> sets;
    for (const auto& e : experiments) {
        if (e.table != f.table) continue;
        const std::string& id = e.spec.id;
        if (!x.rows.count(id)) continue;  // skipped: none of its methods could run
        if (!e.spec.sweep.empty()) {
            for (auto& s : SweepSets(e.spec.sweep, x.rows[id], x.provenance[id])) sets.push_back(s);
        } else {
            sets.push_back({e.spec.group, x.rows[id], x.provenance[id], ""});
        }
    }
    // Variants run only where a checkpoint of theirs is shipped: rows of their own (Tab. 4, 5)
    // or columns of the method's row (the cluster-count table, `rows_are_groups`).
    for (const auto& s : variant_sets[f.table]) sets.push_back(s);
    if (!spec.rows_are_methods) {
        for (const auto& [row, cells] : paper["tables"][f.table]["rows"].items()) {
            (void)cells;
            const bool measured =
                std::any_of(sets.begin(), sets.end(),
                            [&row = row](const ResultSet& s) { return s.row_label == row; });
            if (!measured) to->unavailable[row] = "not trained";
        }
    }
    return sets;
}

/// Every wanted table filled from the experiments (and the variants), in file order.
std::vector<Table> BuildTables(const std::vector<ExperimentFile>& files,
                               const std::vector<PlannedExperiment>& experiments,
                               ExperimentOutputs& x,
                               std::map<std::string, std::vector<ResultSet>>& variant_sets,
                               std::map<std::string, std::vector<ResultSet>>& timing_sets,
                               const std::map<std::string, std::string>& unavailable,
                               const nlohmann::json& paper, const ReproduceOptions& o) {
    std::vector<Table> tables;
    for (const auto& f : files) {
        if (!Wanted(o.tables, f.table)) continue;
        if (!f.timing_of.empty()) {
            if (!x.rows.count(f.timing_of)) continue;
            std::vector<ResultSet> sets = {
                {"", x.rows[f.timing_of], x.provenance[f.timing_of], ""}};
            for (const auto& s : timing_sets[f.table]) sets.push_back(s);
            tables.push_back(
                BuildTimingTable(sets, paper, CpuModel(),
                                 "none (Eigen's own kernels; the classical methods link no BLAS)",
                                 PaperRowLabels()));
            tables.back().title = f.title;
            continue;
        }
        const PaperTableSpec spec = SpecOf(f);
        PaperTableOptions to;
        to.unavailable = unavailable;
        to.paper_rows = PaperRowLabels();
        const std::vector<ResultSet> sets =
            SetsOf(f, spec, experiments, x, variant_sets, paper, &to);
        tables.push_back(BuildPaperTable(spec, sets, paper, to));
        if (sets.empty()) {
            tables.back().notes.push_back(
                "No regbench run fills this table: OGMM (and its variants) are not trained in "
                "this build; the paper's numbers are shown for reference.");
        }
    }
    return tables;
}

std::string CompactMarkdown(const Table& t) { return TableToMarkdown(t, TableForm::kCompact); }
std::string FullMarkdown(const Table& t) { return TableToMarkdown(t, TableForm::kFull); }

/// tables.{md,tex,csv,json} and tables_full.md (every column at its decimals).
void WriteTables(const fs::path& out, const std::string& intro, const std::vector<Table>& tables) {
    const std::string head = "# regbench: the OGMM paper's tables\n\n" + intro + "\n\n";
    WriteText(out / "tables.md",
              head +
                  "Compact form: mean ± 95% CI half-width (the paper's number); every "
                  "column at full precision: tables_full.md.\n\n" +
                  Join(tables, CompactMarkdown));
    WriteText(out / "tables_full.md", head + Join(tables, FullMarkdown));
    WriteText(out / "tables.tex",
              "% " + intro + "\n% needs \\usepackage{booktabs}\n" + Join(tables, TableToLatex));
    WriteText(out / "tables.csv", TablesToCsv(tables));
    WriteText(out / "tables.json", TablesToJson(tables).dump(1) + "\n");
}

/// breakdowns.md and report.html: the tables, then one section per experiment.
void WriteBreakdownsAndHtml(const fs::path& out, const std::string& intro,
                            const std::vector<Table>& tables,
                            const std::vector<PlannedExperiment>& experiments,
                            ExperimentOutputs& x) {
    HtmlReportOptions html;
    html.title = "regbench: reproducing the OGMM paper";
    html.intro = {intro,
                  "Every table's caption names the data each side came from. "
                  "Results: results/*.jsonl; pairs: pairs/*.h5 (this folder)."};
    html.tables = tables;
    std::string breakdowns = "# regbench: breakdowns per experiment\n\n";
    BreakdownOptions bo;
    for (const auto& e : experiments) {
        const std::string& id = e.spec.id;
        if (!x.rows.count(id)) continue;  // skipped: none of its methods could run
        const auto& rows = x.rows[id];
        const Provenance& p = x.provenance[id];
        HtmlSection sec;
        sec.title = fmt::format("{}: {} on {} ({})", id, e.spec.protocol, p.dataset, e.spec.split);
        sec.description = fmt::format(
            "{} pairs, pairing {}, seed {}, {} points, keep {:g}{}; ground-truth CCD floor "
            "{:.4f}.",
            x.pairs[id].pairs.size(), p.pairing, p.seed.dump(), p.points, p.keep,
            e.fallback.empty() ? "" : "; " + e.fallback, p.gt_ccd_floor);
        sec.rows = rows;
        sec.tables = {DistributionTable(rows, bo), StatusTable(rows), RecallTable(rows, bo),
                      CategoryTable(rows, bo), OverlapTable(rows, bo)};
        // Difficulty bins and success-rate curves (issue 54 items 3 and 4).
        for (auto& t : DifficultyTables(rows, bo)) sec.tables.push_back(std::move(t));
        sec.curves = DefaultSuccessCurves();
        for (const auto& c : sec.curves) sec.tables.push_back(SuccessCurveTable(rows, c));
        const PairSet* set = &x.pairs[id];
        sec.pair_lookup = [set](const ResultRow& row) -> const Pair* {
            return row.pair < set->pairs.size() ? &set->pairs[row.pair] : nullptr;
        };
        breakdowns +=
            "## " + sec.title + "\n\n" + sec.description + "\n\n" + Join(sec.tables, FullMarkdown);
        html.sections.push_back(sec);
    }
    WriteText(out / "breakdowns.md", breakdowns);
    WriteText(out / "report.html", RenderHtmlReport(html));
}

}  // namespace

ReproduceSummary Reproduce(const ReproduceOptions& o, std::ostream& log) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<ExperimentFile> files;
    for (const auto& path : o.experiment_files) files.push_back(ReadExperimentFile(path));
    if (files.empty()) files = PaperPlan();
    CheckExperimentFiles(files);
    ValidateOptions(o, files);
    const std::vector<PlannedExperiment> experiments = PlanExperiments(files, o);
    ReproduceSummary summary;
    const fs::path out = fs::absolute(o.out_dir);
    // One reproduce per folder (OUT.lock beside it): a second one, or any regbench writer on
    // the same path, is refused naming the pid before anything is generated.
    fs::path folder = out.lexically_normal();
    if (folder.filename().empty() && folder.has_parent_path()) folder = folder.parent_path();
    CreateParentFolders(folder.string());
    const OutputLock lock(StepLockFolder(o, folder.string()));  // --shard: its own folder
    const WeightsPlan weights = PlanWeights(files, o, out, log);
    fs::create_directories(out / "pairs");
    fs::create_directories(out / "results");
    summary.out_dir = out.string();
    std::map<std::string, std::string> unavailable;
    const auto methods = ChooseAllMethods(files, o, &unavailable, log);
    summary.experiments = experiments.size();
    CheckStep(o, experiments, methods, out.string());  // --prepare, --shard, --render

    ExperimentOutputs x = RunExperiments(experiments, methods, weights, o, out, summary, log);
    const nlohmann::json paper = LoadPaperTables(DefaultPaperTablesPath());
    auto variant_sets = RunVariants(files, methods, x, o, out, summary, log);
    auto timing_sets = RunTimingVariants(files, methods, x, o, out, summary, log);
    if (FinishStep(o, out.string(), summary, log)) return summary;  // --prepare, --shard
    const std::vector<Table> tables =
        BuildTables(files, experiments, x, variant_sets, timing_sets, unavailable, paper, o);

    const std::string intro = fmt::format(
        "regbench {} reproduce{}: {} experiments, seed {}, {} jobs, per-call timeout {} s, "
        "one thread per call; CPU {}.",
        RegbenchVersion(), o.quick ? " --quick" : "", experiments.size(), o.seed, o.jobs,
        o.timeout_seconds, CpuModel());
    WriteTables(out, intro, tables);
    WriteBreakdownsAndHtml(out, intro, tables, experiments, x);
    summary.markdown_path = (out / "tables.md").string();
    summary.html_path = (out / "report.html").string();
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    log << fmt::format("reproduce: done in {:.0f} s ({} pair files generated, {} calls run)\n",
                       secs, summary.pairs_generated, summary.rows_run);
    return summary;
}

}  // namespace regbench
