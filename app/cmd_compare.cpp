// `regbench compare BASE.jsonl NEW.jsonl`: the accuracy regression gate (exit 1 on a
// significant worsening beyond tolerance).
#include <iostream>
#include <optional>

#include "app/cli_numbers.hpp"
#include "app/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/file_lock.hpp"
#include "reports/compare.hpp"
#include "runners/runner.hpp"

namespace regbench::app {

namespace {

/// Thrown to end with exit status 1 after printing the verdict (not an input error).
struct RegressionFound : std::runtime_error {
    RegressionFound() : std::runtime_error("a method got significantly worse beyond tolerance") {}
};

void SetupCompareCommand(CLI::App* cmd) {
    auto base = std::make_shared<std::string>();
    auto candidate = std::make_shared<std::string>();
    auto tolerance = std::make_shared<std::string>("0");
    auto metrics = std::make_shared<std::vector<std::string>>(CompareOptions{}.metrics);
    auto json_out = std::make_shared<std::string>();
    auto o = std::make_shared<CompareOptions>();
    cmd->add_option("base", *base, "Baseline JSONL results")->required();
    cmd->add_option("new", *candidate, "Candidate JSONL results (same pair file)")->required();
    cmd->add_option("--tolerance", *tolerance,
                    "Allowed increase of a metric's mean before a significant worsening fails: "
                    "a number for every metric or METRIC=VALUE,... (metric units)")
        ->capture_default_str();
    // A misspelt metric (mae_R) would be missing from every row and compare nothing: refused.
    cmd->add_option("--metrics", *metrics, "Metrics to test (lower is better)")
        ->delimiter(',')
        ->check(CLI::IsMember({"mae_r", "mae_t", "mse_r", "mse_t", "rre", "rte", "ccd", "chamfer",
                               "overlap_rmse"}))
        ->capture_default_str();
    // alpha outside (0, 1) or NaN makes no change significant: the gate would always pass.
    cmd->add_option("--alpha", o->alpha, "Significance level of the Wilcoxon test, in (0, 1)")
        ->check(OpenInterval(0.0, 1.0))
        ->capture_default_str();
    cmd->add_option("--bootstrap", o->bootstrap_samples, "Paired-bootstrap resamples")
        ->check(PositiveWholeNumber())
        ->capture_default_str();
    cmd->add_option("--seed", o->seed, "Bootstrap seed")
        ->check(WholeNumber())
        ->capture_default_str();
    cmd->add_option("--json", *json_out, "Also write every comparison as JSON to this file");
    cmd->callback([=] {
        // --json onto one of the inputs (by inode, so links count) is refused before reading,
        // and the JSON is written under the output lock, atomically: a full disk or a file-size
        // limit leaves the previous file (or none), never a truncated one.
        std::optional<OutputLock> lock;
        if (!json_out->empty()) {
            CheckOutputPath(*json_out, {*base, *candidate});
            lock.emplace(*json_out);
        }
        ParseTolerance(*tolerance, o.get());
        o->metrics = *metrics;
        const auto result =
            CompareResults(ReadJsonl(*base), ReadJsonl(*candidate), *o, *base, *candidate);
        std::cout << FormatCompareMarkdown(result, *o);
        if (!json_out->empty()) {
            WriteFileAtomic(*json_out,
                            CompareToJson(result, *o)
                                    .dump(2, ' ', false, nlohmann::json::error_handler_t::replace) +
                                "\n",
                            {*base, *candidate});
        }
        if (result.Regressed()) throw RegressionFound();
    });
}

[[maybe_unused]] const bool kCompareRegistered =
    RegisterCommand({"compare",
                     "Paired test of two result files on the same pairs; exit 1 when a method got "
                     "significantly worse beyond --tolerance",
                     SetupCompareCommand});
}  // namespace

}  // namespace regbench::app
