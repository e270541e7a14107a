// `regbench report`: per-method tables from JSONL results.
#include <filesystem>
#include <fstream>
#include <iostream>

#include "app/commands.hpp"
#include "core/atomic_file.hpp"
#include "reports/paper_tables.hpp"
#include "reports/report.hpp"
#include "runners/runner.hpp"

namespace regbench::app {

void AddReportCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("report", "Summarise JSONL results into a table per method");
    auto files = std::make_shared<std::vector<std::string>>();
    auto format = std::make_shared<std::string>("md");
    auto out = std::make_shared<std::string>();
    auto o = std::make_shared<ReportOptions>();
    auto paper = std::make_shared<std::string>();
    auto paper_file = std::make_shared<std::string>(DefaultPaperTablesPath());
    cmd->add_option("results", *files, "One or more JSONL result files (e.g. shards)")->required();
    cmd->add_option("--format,-f", *format, "md | csv | json | latex")
        ->check(CLI::IsMember({"md", "csv", "json", "latex"}));
    cmd->add_option("--out,-o", *out, "Write to this file (atomically) instead of stdout");
    cmd->add_option("--recall-r", o->recall_r_deg, "recall@(r,t): mae_r threshold [deg]");
    cmd->add_option("--recall-t", o->recall_t, "recall@(r,t): mae_t threshold");
    cmd->add_option("--bootstrap", o->bootstrap_samples, "Bootstrap resamples for the 95% CIs");
    cmd->add_option("--paper", *paper,
                    "Also print the paper's cells side by side: TABLE[:GROUP], e.g. "
                    "table1_modelnet_partial:same_category (md format)");
    cmd->add_option("--paper-file", *paper_file, "The paper's tables (JSON)");
    cmd->callback([=] {
        std::vector<nlohmann::json> rows;
        for (const auto& f : *files) {
            auto part = ReadJsonl(f);
            rows.insert(rows.end(), part.begin(), part.end());
        }
        if (rows.empty()) throw std::runtime_error("no result rows in " + files->front());
        const auto summaries = Summarize(rows, *o);
        std::string text;
        if (*format == "md") {
            text = "Data: " + DescribeData(rows) + "\n\n" + FormatMarkdown(summaries, *o);
            if (!paper->empty()) {
                const auto colon = paper->find(':');
                const std::string table = paper->substr(0, colon);
                const std::string group =
                    colon == std::string::npos ? "" : paper->substr(colon + 1);
                text += "\n" + FormatPaperComparison(summaries, LoadPaperTables(*paper_file), table,
                                                     group);
                text += "\nOurs: " + DescribeData(rows) +
                        ". Paper: ModelNet40 / 7Scenes / ICL-NUIM "
                        "as published (their machine, their pairs).\n";
            }
        } else if (*format == "csv") {
            text = FormatCsv(summaries);
        } else if (*format == "latex") {
            text = "% Data: " + DescribeData(rows) + "\n" + FormatLatex(summaries, *o);
        } else {
            text = nlohmann::json{{"data", DescribeData(rows)}, {"methods", ToJson(summaries, *o)}}
                       .dump(2) +
                   "\n";
        }
        if (out->empty()) {
            std::cout << text;
            return;
        }
        WriteFileAtomic(*out, text, *files);  // checked; never replaces an input
    });
}

}  // namespace regbench::app
