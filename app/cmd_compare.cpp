// `regbench compare BASE.jsonl NEW.jsonl`: the accuracy regression gate (exit 1 on a
// significant worsening beyond tolerance or new failed calls, 3 when underpowered).
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "app/cli_numbers.hpp"
#include "app/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/output_rule.hpp"
#include "reports/compare.hpp"
#include "reports/row_access.hpp"
#include "runners/result_row.hpp"

namespace regbench::app {

namespace {

void SetupCompareCommand(CLI::App* cmd) {
    auto base = std::make_shared<std::string>();
    auto candidate = std::make_shared<std::string>();
    auto tolerance = std::make_shared<std::string>();
    auto metrics = std::make_shared<std::vector<std::string>>(CompareOptions{}.metrics);
    auto json_out = std::make_shared<std::string>();
    auto o = std::make_shared<CompareOptions>();
    auto force = std::make_shared<bool>(false);
    cmd->add_option("base", *base, "Baseline JSONL results")->required();
    cmd->add_option("new", *candidate, "Candidate JSONL results (same pair file)")->required();
    CLI::Option* tolerance_flag = cmd->add_option("--tolerance", *tolerance,
                    "Allowed increase of a metric's mean before a significant worsening fails: "
                    "a number for every metric or METRIC=VALUE,... (metric units); metrics not "
                    "named keep their defaults mae_r=0.1,mae_t=0.001,ccd=0.001,rre=0.2,"
                    "rte=0.002");
    // A misspelt metric (mae_R) would be missing from every row and compare nothing: refused.
    cmd->add_option("--metrics", *metrics, "Metrics to test (lower is better)")
        ->delimiter(',')
        ->check(CLI::IsMember(MetricNames()))
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
    cmd->add_option("--min-pairs", o->min_pairs,
                    "A method with fewer matched pairs makes the verdict INCONCLUSIVE (exit 3)")
        ->check(WholeNumber())
        ->capture_default_str();
    cmd->add_flag("--allow-new-failures", o->allow_new_failures,
                  "Do not fail when calls that were ok in the baseline failed, timed out or "
                  "crashed in the candidate");
    cmd->add_option("--json", *json_out, "Also write every comparison as JSON to this file");
    cmd->add_flag("--force", *force, "Replace an existing --json file");
    cmd->footer(
        "Exit status: 0 PASS; 1 FAIL (a significant worsening beyond tolerance, or new failed "
        "calls) or unreadable input; 2 usage error; 3 INCONCLUSIVE (no regression found, but "
        "the pairs cannot detect a worsening as large as the tolerance: the exact Wilcoxon "
        "test needs 2/2^n < alpha, i.e. at least 6 pairs at alpha 0.05).");
    cmd->callback([=] {
        // --json onto one of the inputs (by inode, so links count) is refused before reading,
        // and the JSON is written under the output lock, atomically: a full disk or a file-size
        // limit leaves the previous file (or none), never a truncated one.
        std::optional<ClaimedOutput> claim;  // the one output rule (docs/usage.md, "Outputs")
        if (!json_out->empty()) {
            claim.emplace(*json_out, std::vector<std::string>{*base, *candidate},
                          OutputRule{*force});
        }
        o->metrics = *metrics;
        // Given, even empty (an unset shell variable): parsed, so '' is a usage error, not the
        // defaults silently.
        if (tolerance_flag->count() > 0) {
            try {
                ParseTolerance(*tolerance, o.get());
            } catch (const std::invalid_argument& e) {
                throw CLI::ValidationError(e.what());
            }
        }
        if (!(o->alpha > 0.0 && o->alpha < 1.0)) {
            throw CLI::ValidationError("--alpha must be in (0, 1), got " +
                                       std::to_string(o->alpha));
        }
        if (o->bootstrap_samples < 2) {
            throw CLI::ValidationError("--bootstrap must be at least 2");
        }
        const auto result = CompareResults(ReadResultRows(*base), ReadResultRows(*candidate), *o,
                                           *base, *candidate);
        std::cout << FormatCompareMarkdown(result, *o);
        if (!json_out->empty()) {
            WriteFileAtomic(*json_out,
                            CompareToJson(result, *o)
                                    .dump(2, ' ', false, nlohmann::json::error_handler_t::replace) +
                                "\n",
                            {*base, *candidate});
        }
        const int code = VerdictExitCode(result.Verdict());
        if (code != 0) throw CLI::RuntimeError(code);
    });
}

[[maybe_unused]] const bool kCompareRegistered =
    RegisterCommand({"compare",
                     "Paired test of two result files on the same pairs; exit 1 when a method got "
                     "significantly worse beyond --tolerance or has new failed calls, 3 when "
                     "the pairs are too few to tell",
                     SetupCompareCommand});
}  // namespace

}  // namespace regbench::app
