// `regbench report`: per-method tables from JSONL results, one table per pair file and
// Euler convention (rows from different data are never pooled).
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

#include "app/cli_numbers.hpp"
#include "app/cli_params.hpp"
#include "app/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/output_rule.hpp"
#include "reports/breakdown.hpp"
#include "reports/curves.hpp"
#include "reports/paper_tables.hpp"
#include "reports/report.hpp"
#include "reports/timing.hpp"
#include "reports/versus.hpp"
#include "runners/registry.hpp"
#include "runners/result_row.hpp"

namespace regbench::app {
namespace {

/// `--curves` and `--breakdown`: for each result table, its success curves and difficulty
/// tables over its own rows, titled with its pair file when there are several.
std::vector<Table> ExtraTables(const std::vector<ReportTable>& tables, bool curves,
                               bool breakdown) {
    std::vector<Table> out;
    for (const ReportTable& rt : tables) {
        std::vector<ResultRow> rows;
        for (const ResultRow* r : rt.rows) rows.push_back(*r);
        std::vector<Table> extra;
        // Lengths in the pair file's units: the unit-sphere ranges times its scale.
        const double scale = rt.data.scale;
        if (curves) {
            for (auto c : DefaultSuccessCurves()) {
                if (c.metric != "rre") c.max *= scale;
                extra.push_back(SuccessCurveTable(rows, c));
            }
        }
        if (breakdown) {
            BreakdownOptions bo;
            for (double& edge : bo.translation_edges) edge *= scale;
            for (auto& t : DifficultyTables(rows, bo)) extra.push_back(t);
        }
        for (auto& t : extra) {
            t.id = rt.data.pairs_file + ":" + t.id;
            if (tables.size() > 1) t.title += " (" + rt.data.pairs_file + ")";
            out.push_back(std::move(t));
        }
    }
    return out;
}

// Long on purpose: a flat list of the command's options (CLI11), one statement each, in the
// order --help prints them; the work is in reports/.
void SetupReportCommand(CLI::App* cmd) {
    auto files = std::make_shared<std::vector<std::string>>();
    auto format = std::make_shared<std::string>("md");
    auto out = std::make_shared<std::string>();
    auto o = std::make_shared<ReportOptions>();
    auto euler = std::make_shared<std::string>();
    auto paper = std::make_shared<std::string>();
    auto paper_file = std::make_shared<std::string>(DefaultPaperTablesPath());
    auto full = std::make_shared<bool>(false);
    auto force = std::make_shared<bool>(false);
    cmd->add_option("results", *files, "One or more JSONL result files (e.g. shards)")->required();
    cmd->add_option("--format,-f", *format, "md | csv | json | latex")
        ->check(CLI::IsMember({"md", "csv", "json", "latex"}))
        ->capture_default_str();
    cmd->add_option("--out,-o", *out, "Write to this file (atomically) instead of stdout");
    cmd->add_flag("--force", *force, "Replace an existing --out");
    // Thresholds and resamples checked as text (nan, inf, -1, 0 are usage errors: nan made
    // every recall 0 silently).
    cmd->add_option("--recall-r", o->recall_r_deg, "recall@(r,t): mae_r < r [deg]")
        ->capture_default_str()
        ->check(PositiveReal());
    cmd->add_option("--recall-t", o->recall_t,
                    "recall@(r,t): mae_t < t (default 0.1 times the pair file's scale)")
        ->capture_default_str()
        ->check(PositiveReal());
    cmd->add_option("--success-rre", o->success_rre_deg, "success: rre < this [deg] (and rte)")
        ->capture_default_str()
        ->check(PositiveReal());
    cmd->add_option("--success-rte", o->success_rte,
                    "success: rte < this (and rre); default 0.1 times the pair file's scale")
        ->capture_default_str()
        ->check(PositiveReal());
    cmd->add_option("--success-rule", o->success_rule,
                    "The success column's rule: rre-rte (--success-rre/--success-rte) or a "
                    "preset: paper-recall (mae_r<1, mae_t<0.1), 3dmatch-rmse (RMSE of the "
                    "ground-truth correspondences < 0.2), kitti (rre<5, rte<2), 3dmatch-rre-rte "
                    "(rre<15, rte<0.3); docs/metrics.md, \"Conventions\"")
        ->capture_default_str()
        ->check(CLI::IsMember(SuccessRuleNames()));
    auto rre_rte_over = std::make_shared<std::string>("all");
    cmd->add_option("--rre-rte-over", *rre_rte_over,
                    "Pairs the rre/rte means average over: all (with finite metrics) or "
                    "successful (those the success rule accepts, as GeoTransformer's KITTI eval)")
        ->capture_default_str()
        ->check(CLI::IsMember({"all", "successful"}));
    auto rates_per = std::make_shared<std::string>("pair");
    cmd->add_option("--rates-per", *rates_per,
                    "Rates (recall, success) over pairs, or the mean of per-scene (the pairs' "
                    "shape) or per-category rates, as 3DMatch's scene-averaged recall")
        ->capture_default_str()
        ->check(CLI::IsMember({"pair", "scene", "category"}));
    auto curves = std::make_shared<bool>(false);
    cmd->add_flag("--curves", *curves,
                  "Add success rate against threshold (rre to 15 deg, rte to 0.3) with the area "
                  "under each curve, per pair file");
    auto breakdown = std::make_shared<bool>(false);
    cmd->add_flag("--breakdown", *breakdown,
                  "Add mae_r per easy / medium / hard bin of the ground truth's rotation and "
                  "translation and of the overlap, with counts, per pair file (docs/reports.md)");
    cmd->add_flag("--recall-3dmatch", o->recall_3dmatch,
                  "Add the 3DMatch-style recall: overlap RMSE < 0.2, rre < 15 deg, rte < 0.3");
    cmd->add_option("--euler", *euler,
                    "Report mae_r/rmse_r in this convention (zyx: the paper's, xyz: RPMNet's); "
                    "default: the rows' own. Rows in another one are recomputed from their "
                    "stored ground truth")
        ->check(CLI::IsMember({"zyx", "xyz"}));
    cmd->add_option("--bootstrap", o->bootstrap_samples, "Bootstrap resamples for the 95% CIs")
        ->capture_default_str()
        ->check(PositiveWholeNumber());
    cmd->add_option("--paper", *paper,
                    "Also print the paper's cells side by side, with our pair counts: "
                    "TABLE[:GROUP], e.g. table1:same_category (TABLE: a table id or a prefix of "
                    "one, as reproduce --tables takes them; GROUP: one of its column groups; "
                    "every format: one more table after each result table)");
    cmd->add_flag("--common-pairs", o->common_pairs,
                  "When the methods of one pair file were run on different pairs (a shard, an "
                  "unfinished run), compare them on the pairs they share (the caption says so) "
                  "instead of refusing");
    cmd->add_option("--paper-file", *paper_file, "The paper's tables (JSON)");
    cmd->add_flag("--full", *full,
                  "Markdown: every column at its decimals (rre, rte, rmse, mean s too) instead of "
                  "the compact table (mean ± CI half-width rounded to the CI)");
    auto versus = std::make_shared<std::string>();
    cmd->add_option("--versus", *versus,
                    "A,B: instead of the summary, method A against method B on the pairs both "
                    "ran, per metric: the mean of A - B with its 95% CI and p from one paired "
                    "bootstrap (they cannot disagree), A's wins, ties and losses and a verdict "
                    "line (one table per pair file; docs/reports.md)");
    cmd->callback([=] {
        const auto comma = versus->find(',');
        const std::string a = versus->substr(0, comma);
        const std::string b = comma == std::string::npos ? "" : versus->substr(comma + 1);
        if (!versus->empty() &&
            (a.empty() || b.empty() || b.find(',') != std::string::npos || a == b)) {
            throw CLI::ValidationError("--versus takes two different method names, A,B; got '" +
                                       *versus + "'");
        }
        if (!versus->empty() && (!paper->empty() || !euler->empty())) {
            throw CLI::ValidationError(
                "--versus compares the rows as scored (their own Euler convention); it takes "
                "neither --paper nor --euler");
        }
        if (!versus->empty() && (*curves || *breakdown)) {
            throw CLI::ValidationError("--versus prints the comparison only; it takes neither "
                                       "--curves nor --breakdown");
        }
        // The one output rule (docs/usage.md, "Outputs") before reading anything; then one
        // writer per --out until the report is in place.
        // --paper's table and group before anything is read (a usage error, exit 2).
        nlohmann::json published;
        PaperSelection selection;
        if (!paper->empty()) {
            published = LoadPaperTables(*paper_file);
            selection = AsUsageError([&] { return ResolvePaperSelection(published, *paper); });
        }
        std::optional<ClaimedOutput> claim;
        if (!out->empty()) claim.emplace(*out, *files, OutputRule{*force});
        std::vector<ResultRow> rows;
        for (const auto& f : *files) {
            auto part = ReadResultRows(f);  // throws naming file:line
            rows.insert(rows.end(), part.begin(), part.end());
        }
        if (rows.empty()) throw std::runtime_error("no result rows in " + files->front());
        ReportOptions opts = *o;
        opts.recall_t_given = cmd->count("--recall-t") > 0;
        opts.success_rte_given = cmd->count("--success-rte") > 0;
        if (!euler->empty()) opts.euler = ParseEulerConvention(*euler);
        opts.rre_rte_over = ParseErrorPairs(*rre_rte_over);
        opts.rates_per = ParseRatePer(*rates_per);
        std::vector<ReportTable> tables;
        std::vector<Table> out_tables;
        if (!versus->empty()) {
            for (const auto& r : CompareMethods(rows, a, b)) {
                out_tables.push_back(VersusTable(r));
            }
        } else {
            tables = BuildTables(rows, opts);
            out_tables = SummaryTables(tables, opts);
            for (auto& t : TimingTables(tables)) out_tables.push_back(std::move(t));
            for (auto& t : ExtraTables(tables, *curves, *breakdown)) {
                out_tables.push_back(std::move(t));
            }
        }
        if (!paper->empty()) {
            // TABLE[:GROUP] of the paper beside each result table.
            for (const auto& t : tables) {
                out_tables.push_back(PaperComparisonTable(t, published, selection.table,
                                                          selection.group, PaperRowLabels()));
            }
        }
        std::string text;
        if (*format == "md") {
            text = TablesToMarkdown(out_tables, *full ? TableForm::kFull : TableForm::kCompact);
        } else if (*format == "csv") {
            text = TablesToCsv(out_tables);
        } else if (*format == "latex") {
            for (const auto& t : out_tables) text += (text.empty() ? "" : "\n") + TableToLatex(t);
        } else {
            text = TablesToJson(out_tables).dump(2) + "\n";
        }
        if (tables.size() > 1) {
            std::cerr << "[report] rows come from " << tables.size()
                      << " different pair files / conventions: one table each, never pooled\n";
        }
        if (out->empty()) {
            std::cout << text;
        } else {
            WriteFileAtomic(*out, text, *files);  // checked; never replaces an input
        }
    });
}

[[maybe_unused]] const bool kReportRegistered = RegisterCommand(
    {"report",
     "Summarise JSONL results: one table per pair file and Euler convention, a row per "
     "method and parameter set (metrics: docs/metrics.md)",
     SetupReportCommand});
}  // namespace

}  // namespace regbench::app
