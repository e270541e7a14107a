#include "reports/reproduce.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <ostream>
#include <set>
#include <utility>

#include "core/atomic_file.hpp"
#include "core/file_lock.hpp"
#include "core/version.hpp"
#include "datasets/dataset_shapes.hpp"
#include "protocols/generate.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_hash.hpp"
#include "protocols/pair_summary.hpp"
#include "reports/breakdown.hpp"
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

/// One pair file and its results: fills one column group of one paper table.
struct Experiment {
    std::string id;     ///< file stem, e.g. "tab1_same"
    std::string table;  ///< paper table id
    std::string group;  ///< column group ("" for none)
    std::string protocol;
    std::string dataset;  ///< name or path
    std::string split;
    std::string fallback;  ///< non-empty when standing in for the paper's dataset
    std::size_t pairs = 0;
    std::uint64_t seed = 1;
    bool sweep = false;         ///< overlap-sweep: rows split into groups by pair % levels
    std::string pairing;        ///< "" = the protocol's default (independent)
    bool noise_free = false;    ///< noise sigma 0 (the clean c2c variant)
    bool one_per_item = false;  ///< one pair per item of the split (`generate --pairs all`)
};

const std::vector<std::string> kSweepGroups = {"30%", "40%", "50%", "60%", "70%"};

/// Learned methods whose rows say "not trained" when they cannot be created.
const std::set<std::string> kLearned = {"ogmm", "deepgmr"};

bool Wanted(const std::vector<std::string>& wanted, const std::string& table) {
    if (wanted.empty()) return true;
    for (const auto& w : wanted) {
        if (table.rfind(w, 0) == 0) return true;
    }
    return false;
}

/// Every experiment of the paper's tables, in the paper's order, then those the wanted tables
/// need. Long because it is the list itself: one entry (and its stand-in data) per table part.
std::vector<Experiment> PlanExperiments(const ReproduceOptions& o) {
    const std::size_t n = o.pairs > 0 ? o.pairs : (o.quick ? 10 : 1000);
    const bool mn = !o.modelnet40.empty();
    const std::string objects = mn ? o.modelnet40 : "cgal";
    const std::string object_fallback = mn ? "" : "embedded CGAL mesh corpus instead of ModelNet40";
    const auto make = [&](std::string id, std::string table, std::string group,
                          std::string protocol, std::string dataset, std::string split,
                          std::string fallback, std::size_t pairs, std::uint64_t seed) {
        Experiment e;
        e.id = std::move(id);
        e.table = std::move(table);
        e.group = std::move(group);
        e.protocol = std::move(protocol);
        e.dataset = std::move(dataset);
        e.split = std::move(split);
        e.fallback = std::move(fallback);
        e.pairs = pairs;
        e.seed = seed;
        return e;
    };
    const auto obj = [&](std::string id, std::string table, std::string group, std::string protocol,
                         std::string split, std::size_t pairs) {
        return make(std::move(id), std::move(table), std::move(group), std::move(protocol),
                    objects, std::move(split), object_fallback, pairs, o.seed);
    };
    std::vector<Experiment> all = {
        obj("tab1_same", "table1_modelnet_partial", "same_category", "partial",
            "same_category/test", n),
        obj("tab1_cross", "table1_modelnet_partial", "cross_category", "partial",
            "cross_category/test", n),
        obj("tab2_jitter", "table2_modelnet_noise_density", "jitter", "jitter",
            "same_category/test", n),
        obj("tab2_density", "table2_modelnet_noise_density", "density", "density",
            "same_category/test", n),
    };
    // Indoor scenes: real data when given, else the indoor simulation (different seeds so
    // the two columns are not the same pairs).
    const std::size_t n_indoor = std::max<std::size_t>(4, n / 2);
    all.push_back(make("tab3_7scenes", "table3_indoor", "7scenes", "indoor",
                       o.sevenscenes.empty() ? "indoor-sim" : o.sevenscenes, "test",
                       o.sevenscenes.empty() ? "simulated indoor scans instead of 7Scenes" : "",
                       n_indoor, o.seed));
    all.push_back(make("tab3_icl_nuim", "table3_indoor", "icl_nuim", "indoor",
                       o.icl_nuim.empty() ? "indoor-sim" : o.icl_nuim, "test",
                       o.icl_nuim.empty() ? "simulated indoor scans instead of ICL-NUIM" : "",
                       n_indoor, o.seed + 1));
    // Real ICL-NUIM: its test file's stored pairs, as DeepGMR's and the authors' evaluation.
    if (!o.icl_nuim.empty()) all.back().pairing = "stored";
    // Sweep: half the pairs per level (500 of 1000); --quick 2 per level.
    const std::size_t n_sweep =
        o.quick && o.pairs == 0 ? 2 * kSweepGroups.size() : n * kSweepGroups.size() / 2;
    Experiment sweep = obj("supp_overlap", "supp_overlap_ratio", "", "overlap-sweep",
                           "same_category/test", n_sweep);
    sweep.sweep = true;
    all.push_back(sweep);
    all.push_back(obj("supp_c2c", "supp_complete", "c2c", "complete", "same_category/test", n));
    all.push_back(
        obj("supp_c2p", "supp_complete", "c2p", "complete-to-partial", "same_category/test", n));
    // The paper's CPD c2c CCD (0.0037) is below the noisy protocol's floor: offer the clean,
    // shared-sample variant beside it.
    Experiment clean =
        obj("supp_c2c_clean", "supp_complete", "c2c_clean", "complete", "same_category/test", n);
    clean.pairing = "shared";
    clean.noise_free = true;
    all.push_back(clean);
    // Full runs on real data use every test item once (as the authors evaluate), unless
    // --pairs fixes the count; --quick and the fallbacks keep the fixed count.
    if (o.pairs == 0 && !o.quick) {
        for (auto& e : all) {
            const bool real = e.fallback.empty();
            e.one_per_item = real;
        }
    }
    std::vector<Experiment> out;
    for (const auto& e : all) {
        // Tab. 6 times the Tab. 1 same-category runs; the ablations (Tab. 4, 5) run their
        // variants on the same pairs.
        if (Wanted(o.tables, e.table) ||
            (e.id == "tab1_same" && (Wanted(o.tables, "table6_inference_time") ||
                                     Wanted(o.tables, "table4_ablation_components") ||
                                     Wanted(o.tables, "table5_ablation_losses")))) {
            out.push_back(e);
        }
    }
    return out;
}

/// Writes `text` to `path` atomically and checked (core/atomic_file).
void WriteText(const fs::path& path, const std::string& text) {
    WriteFileAtomic(path.string(), text);
}

/// Methods to run, and the reasons the wanted ones that cannot run are left out.
std::vector<MethodSpec> ChooseMethods(const ReproduceOptions& o,
                                      std::map<std::string, std::string>* unavailable,
                                      std::ostream& log) {
    std::vector<std::string> names = o.methods;
    if (names.empty()) {
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
            if (!o.methods.empty() && !kLearned.count(name)) throw;
            (*unavailable)[name] = "not trained";
            log << "reproduce: " << name << " left out (not trained: " << e.what() << ")\n";
        }
    }
    for (const auto& learned : kLearned) {
        bool registered = false;
        for (const auto& m : AllMethods()) registered |= m.name == learned;
        if (!registered && !unavailable->count(learned)) {
            (*unavailable)[learned] = "not trained";
            log << "reproduce: " << learned << " is not registered in this build: not trained\n";
        }
    }
    if (specs.empty()) throw std::runtime_error("reproduce: no method can run");
    return specs;
}

/// Generates the pair file unless a previous invocation did.
bool EnsurePairs(const Experiment& e,
                 const fs::path& path,
                 const ReproduceOptions& o,
                 std::ostream& log) {
    if (fs::exists(path)) return false;
    GenerateRequest request;
    request.dataset = e.dataset;
    request.split = e.split;
    request.num_pairs = e.pairs;
    request.seed = e.seed;
    request.options = DefaultProtocolOptions(ParseProtocol(e.protocol));
    if (!e.pairing.empty()) request.options.pairing = ParsePairing(e.pairing);
    if (e.noise_free) request.options.noise_sigma = 0.0;
    request.one_per_item = e.one_per_item;
    request.out = path.string();
    request.extra_provenance = {{"regbench_version", RegbenchVersion()},
                                {"reproduce_experiment", e.id}};
    if (!e.fallback.empty()) request.extra_provenance["fallback"] = e.fallback;
    DatasetOptions dataset_options;
    dataset_options.data_dir = o.data_dir;
    log << fmt::format("reproduce: {}: generating {} {} pairs ({} pairing{}) from {} ({})\n", e.id,
                       e.one_per_item ? "one per item" : std::to_string(e.pairs), e.protocol,
                       e.pairing.empty() ? "independent" : e.pairing,
                       e.noise_free ? ", noise-free" : "", e.dataset, e.split);
    GenerateToFile(request, DatasetShapeLoader(dataset_options));
    return true;
}

/// Splits a sweep's rows into its levels (pair k has level k % levels).
std::vector<ResultSet> SweepSets(const std::vector<nlohmann::json>& rows, const Provenance& p) {
    std::vector<ResultSet> sets;
    for (std::size_t l = 0; l < kSweepGroups.size(); ++l) {
        ResultSet s{kSweepGroups[l], {}, p, ""};
        for (const auto& r : rows) {
            if (r.value("pair", 0UL) % kSweepGroups.size() == l) s.rows.push_back(r);
        }
        sets.push_back(s);
    }
    return sets;
}

/// How `reproduce` runs methods on one pair file: its jobs, per-call timeout and progress,
/// resuming the finished rows of a previous invocation.
RunOptions ExperimentRun(const ReproduceOptions& o,
                         const fs::path& pairs,
                         std::vector<MethodSpec> methods,
                         const fs::path& results) {
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

std::string Join(const std::vector<Table>& tables, std::string (*fn)(const Table&)) {
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
    for (const auto& s : PaperTableSpecs()) ids.push_back(s.id);
    ids.insert(ids.begin() + 5, "table6_inference_time");
    return ids;
}

namespace {

/// Refuses table names that match no table and dataset paths that do not exist, before any
/// work starts.
void ValidateOptions(const ReproduceOptions& o) {
    if (o.jobs < 1) throw std::invalid_argument("--jobs must be at least 1");
    if (!(o.timeout_seconds >= 0.0)) throw std::invalid_argument("--timeout must be >= 0");
    for (const auto& t : o.tables) {
        bool known = false;
        for (const auto& id : ReproducibleTables()) known |= id.rfind(t, 0) == 0;
        if (!known) {
            std::string list;
            for (const auto& id : ReproducibleTables()) list += (list.empty() ? "" : ", ") + id;
            throw std::invalid_argument("--tables: '" + t + "' names no table (" + list + ")");
        }
    }
    for (const auto& [flag, path] :
         {std::pair<const char*, std::string>{"--modelnet40", o.modelnet40},
          {"--7scenes", o.sevenscenes},
          {"--icl-nuim", o.icl_nuim}}) {
        if (!path.empty() && !fs::exists(path)) {
            throw std::invalid_argument(std::string(flag) + " " + path +
                                        ": no such file or folder");
        }
    }
}

/// Each experiment's result rows, pair-file provenance and pairs, by experiment id.
struct ExperimentOutputs {
    std::map<std::string, std::vector<nlohmann::json>> rows;
    std::map<std::string, Provenance> provenance;
    std::map<std::string, PairSet> pairs;
};

/// Generates and runs every experiment; each step is skipped or resumed when done before.
ExperimentOutputs RunExperiments(const std::vector<Experiment>& experiments,
                                 const std::vector<MethodSpec>& methods,
                                 const ReproduceOptions& o,
                                 const fs::path& out,
                                 ReproduceSummary& summary,
                                 std::ostream& log) {
    ExperimentOutputs x;
    for (const auto& e : experiments) {
        const fs::path pairs = out / "pairs" / (e.id + ".h5");
        const fs::path results = out / "results" / (e.id + ".jsonl");
        summary.pairs_generated += EnsurePairs(e, pairs, o, log) ? 1 : 0;
        const RunOptions run = ExperimentRun(o, pairs, methods, results);
        log << "reproduce: " << e.id << ": running " << methods.size() << " methods\n";
        summary.rows_run += RunBenchmark(run).rows_written;
        x.rows[e.id] = ReadJsonl(results.string());
        x.provenance[e.id] = ProvenanceOfPairFile(pairs.string());
        x.provenance[e.id].fallback = e.fallback;
        x.pairs[e.id] = ReadPairFile(pairs.string());
    }
    return x;
}

/// Ablation rows (Tab. 4, 5): every variant with a shipped checkpoint
/// (data/models/ablation/<kind>/<paper row>, written by `regbench train --ablation`) runs as
/// `ogmm` on the Tab. 1 same-category pairs; variants without one say "not trained" (in
/// BuildTables). Returns the variants' result sets by table id.
std::map<std::string, std::vector<ResultSet>> RunAblations(
    [[maybe_unused]] const std::vector<MethodSpec>& methods,
    [[maybe_unused]] const ExperimentOutputs& x,
    [[maybe_unused]] const nlohmann::json& paper,
    [[maybe_unused]] const ReproduceOptions& o,
    [[maybe_unused]] const fs::path& out,
    [[maybe_unused]] ReproduceSummary& summary,
    [[maybe_unused]] std::ostream& log) {
    std::map<std::string, std::vector<ResultSet>> ablation_sets;
#ifdef REGBENCH_HAVE_LEARNED
    const bool ogmm_runs = std::any_of(methods.begin(), methods.end(),
                                       [](const MethodSpec& m) { return m.name == "ogmm"; });
    for (const auto& [table, kind] :
         {std::pair<std::string, std::string>{"table4_ablation_components", "components"},
          {"table5_ablation_losses", "losses"}}) {
        if (!Wanted(o.tables, table) || !x.rows.count("tab1_same")) continue;
        if (!ogmm_runs) {
            log << "reproduce: " << table << ": ogmm cannot run, its variants are not run\n";
            continue;
        }
        for (const auto& [row, cells] : paper["tables"][table]["rows"].items()) {
            (void)cells;
            const std::string dir = ShippedCheckpointDir("ablation/" + kind + "/" + row);
            if (!fs::exists(fs::path(dir) / "checkpoint.json")) continue;
            MethodSpec spec{"ogmm", FindMethod("ogmm").defaults};
            spec.params["checkpoint"] = dir;
            std::string stem = "ablation_" + kind + "_" + row;
            std::replace(stem.begin(), stem.end(), '+', '_');
            const RunOptions run = ExperimentRun(o, out / "pairs" / "tab1_same.h5", {spec},
                                                 out / "results" / (stem + ".jsonl"));
            log << "reproduce: " << table << ": variant " << row << " (checkpoint " << dir << ")\n";
            summary.rows_run += RunBenchmark(run).rows_written;
            ablation_sets[table].push_back(
                {"", ReadJsonl(run.out_path), x.provenance.at("tab1_same"), row});
        }
    }
#endif
    return ablation_sets;
}

/// The paper's tables filled from the experiments (and the ablation variants), in the
/// paper's order, with Tab. 6 (timing) after Tab. 5.
std::vector<Table> BuildTables(const std::vector<Experiment>& experiments,
                               ExperimentOutputs& x,
                               std::map<std::string, std::vector<ResultSet>>& ablation_sets,
                               const std::map<std::string, std::string>& unavailable,
                               const nlohmann::json& paper,
                               const ReproduceOptions& o) {
    PaperTableOptions table_options;
    table_options.unavailable = unavailable;
    std::vector<Table> tables;
    for (const auto& spec : PaperTableSpecs()) {
        if (!Wanted(o.tables, spec.id)) continue;
        std::vector<ResultSet> sets;
        for (const auto& e : experiments) {
            if (e.table != spec.id) continue;
            if (e.sweep) {
                for (auto& s : SweepSets(x.rows[e.id], x.provenance[e.id])) sets.push_back(s);
            } else {
                sets.push_back({e.group, x.rows[e.id], x.provenance[e.id], ""});
            }
        }
        PaperTableOptions to = table_options;
        if (!spec.rows_are_methods) {
            // Ablation variants run only where a checkpoint of theirs is shipped.
            for (const auto& s : ablation_sets[spec.id]) sets.push_back(s);
            for (const auto& [row, cells] : paper["tables"][spec.id]["rows"].items()) {
                (void)cells;
                const bool measured =
                    std::any_of(sets.begin(), sets.end(),
                                [&row = row](const ResultSet& s) { return s.row_label == row; });
                if (!measured) to.unavailable[row] = "not trained";
            }
        }
        tables.push_back(BuildPaperTable(spec, sets, paper, to));
        if (sets.empty()) {
            tables.back().notes.push_back(
                "No regbench run fills this table: OGMM (and its variants) are not trained in "
                "this build; the paper's numbers are shown for reference.");
        }
        if (spec.id == "table5_ablation_losses" && Wanted(o.tables, "table6_inference_time") &&
            x.rows.count("tab1_same")) {
            tables.push_back(BuildTimingTable(
                {{"", x.rows["tab1_same"], x.provenance["tab1_same"], ""}}, paper, CpuModel(),
                "none (Eigen's own kernels; the classical methods link no BLAS)"));
        }
    }
    return tables;
}

/// tables.{md,tex,csv,json}.
void WriteTables(const fs::path& out, const std::string& intro, const std::vector<Table>& tables) {
    WriteText(out / "tables.md", "# regbench: the OGMM paper's tables\n\n" + intro + "\n\n" +
                                     Join(tables, TableToMarkdown));
    WriteText(out / "tables.tex",
              "% " + intro + "\n% needs \\usepackage{booktabs}\n" + Join(tables, TableToLatex));
    WriteText(out / "tables.csv", TablesToCsv(tables));
    WriteText(out / "tables.json", TablesToJson(tables).dump(1) + "\n");
}

/// breakdowns.md and report.html: the tables, then one section per experiment.
void WriteBreakdownsAndHtml(const fs::path& out,
                            const std::string& intro,
                            const std::vector<Table>& tables,
                            const std::vector<Experiment>& experiments,
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
        const auto& rows = x.rows[e.id];
        const Provenance& p = x.provenance[e.id];
        HtmlSection sec;
        sec.title = fmt::format("{}: {} on {} ({})", e.id, e.protocol, p.dataset, e.split);
        sec.description = fmt::format(
            "{} pairs, pairing {}, seed {}, {} points, keep {:g}{}; ground-truth CCD floor "
            "{:.4f}.",
            x.pairs[e.id].pairs.size(), p.pairing, p.seed.dump(), p.points, p.keep,
            e.fallback.empty() ? "" : "; " + e.fallback, p.gt_ccd_floor);
        sec.rows = rows;
        sec.tables = {DistributionTable(rows, bo), StatusTable(rows), RecallTable(rows, bo),
                      CategoryTable(rows, bo), OverlapTable(rows, bo)};
        const PairSet* set = &x.pairs[e.id];
        sec.pair_lookup = [set](const nlohmann::json& row) -> const Pair* {
            const auto k = row.value("pair", static_cast<std::size_t>(-1));
            return k < set->pairs.size() ? &set->pairs[k] : nullptr;
        };
        breakdowns += "## " + sec.title + "\n\n" + sec.description + "\n\n" +
                      Join(sec.tables, TableToMarkdown);
        html.sections.push_back(sec);
    }
    WriteText(out / "breakdowns.md", breakdowns);
    WriteText(out / "report.html", RenderHtmlReport(html));
}

}  // namespace

ReproduceSummary Reproduce(const ReproduceOptions& o, std::ostream& log) {
    const auto start = std::chrono::steady_clock::now();
    ValidateOptions(o);
    ReproduceSummary summary;
    const fs::path out = fs::absolute(o.out_dir);
    // One reproduce per folder (OUT.lock beside it): a second one, or any regbench writer on
    // the same path, is refused naming the pid before anything is generated.
    fs::path folder = out.lexically_normal();
    if (folder.filename().empty() && folder.has_parent_path()) folder = folder.parent_path();
    const OutputLock lock(folder.string());
    fs::create_directories(out / "pairs");
    fs::create_directories(out / "results");
    summary.out_dir = out.string();
    std::map<std::string, std::string> unavailable;
    const auto methods = ChooseMethods(o, &unavailable, log);
    const auto experiments = PlanExperiments(o);
    summary.experiments = experiments.size();

    ExperimentOutputs x = RunExperiments(experiments, methods, o, out, summary, log);
    const nlohmann::json paper = LoadPaperTables(DefaultPaperTablesPath());
    auto ablation_sets = RunAblations(methods, x, paper, o, out, summary, log);
    const std::vector<Table> tables =
        BuildTables(experiments, x, ablation_sets, unavailable, paper, o);

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
