// `regbench score`: result rows for transforms computed outside regbench (any language), so
// `report` treats external and built-in methods alike.
#include <fmt/format.h>

#include <iostream>

#include "app/cli_numbers.hpp"
#include "app/cli_params.hpp"
#include "app/commands.hpp"
#include "core/output_rule.hpp"
#include "runners/score.hpp"

namespace regbench::app {

namespace {

void SetupScoreCommand(CLI::App* cmd) {
    auto o = std::make_shared<ScoreOptions>();
    auto params = std::make_shared<std::string>();
    auto euler = std::make_shared<std::string>("zyx");
    auto force = std::make_shared<bool>(false);
    cmd->add_option("--pairs", o->pairs_path, "Frozen HDF5 pair file the transforms belong to")
        ->required();
    cmd->add_option("--transforms", o->transforms_path,
                    "Format by extension: T.jsonl ({\"pair\": k, \"transform\": [[4x4]], "
                    "\"seconds\": s} per line), T.csv (pair,t00,...,t23 or pair,t00,...,t33, "
                    "row-major[,seconds]), T.log (3DMatch: 'i j n' then the 4 rows of the 4x4, "
                    "record k = pair k) or T.npy (NumPy (P,4,4) float64/float32, element k = pair "
                    "k); docs/metrics.md#scoring-external-transforms")
        ->required()
        ->check(CLI::Validator(
            [](const std::string& path) {
                return TransformsFormatOf(path) == TransformsFormat::kUnknown
                           ? "'" + path + "': " + kTransformsExtensions
                           : std::string();
            },
            "FORMAT", "transforms format"));
    cmd->add_option("--method", o->method, "Method name written in every row")->required();
    cmd->add_option("--params", *params, "JSON object of the method's parameters, recorded");
    cmd->add_option("--out", o->out_path, "Output JSONL (written atomically)")->required();
    cmd->add_option("--euler", *euler,
                    "Euler angles of mae_r/rmse_r: zyx = scipy as_euler('zyx'), the paper's; "
                    "xyz = RPMNet's")
        ->check(CLI::IsMember({"zyx", "xyz"}))
        ->capture_default_str();
    cmd->add_option("--rigid-tol", o->rigid_tolerance,
                    "Reject a transform when max|R^T R - I|, |det R - 1| or its bottom row's "
                    "distance from (0,0,0,1) exceeds this")
        // NaN would accept every matrix, and so would 1e18 (diag(5, 0.1, 3) scored ok): a
        // tolerance above kMaxRigidTolerance accepts matrices far from any rotation.
        ->check(ClosedInterval(0.0, kMaxRigidTolerance))
        ->capture_default_str();
    cmd->add_flag("--allow-scale", o->allow_scale,
                  "Accept similarities s R (uniform scale, e.g. CPD with scale): the rotation "
                  "metrics use R, the row's scale is s");
    cmd->add_flag("--allow-unhashed", o->allow_unhashed,
                  "Score a transforms file that records no content hash of its pair file "
                  "(refused by default: nothing shows it was computed on --pairs)");
    AddMetricOptions(cmd, &o->metric_options);
    cmd->add_option("--threads", o->threads, "Threads the method used (recorded in rows)")
        ->check(ThreadCount())
        ->capture_default_str();
    cmd->add_flag("--force", *force, "Replace an existing --out");
    cmd->callback([=] {
        // The one output rule (docs/usage.md, "Outputs"); the scorer takes the lock.
        CheckOutputRule(o->out_path, {o->pairs_path, o->transforms_path}, OutputRule{*force});
        ScoreOptions opts = *o;
        opts.params = ParseParamsOption(*params);
        opts.ccd_clip_given = cmd->count("--ccd-clip") > 0;
        opts.euler = ParseEulerConvention(*euler);
        const ScoreSummary s = ScoreTransforms(opts);
        std::cerr << fmt::format("[score] wrote {} rows ({} missing) to {}\n", s.rows, s.missing,
                                 opts.out_path);
    });
}

[[maybe_unused]] const bool kScoreRegistered = RegisterCommand(
    {"score",
     "Score transforms computed elsewhere on a pair file; writes the same rows as `run` "
     "(formats: docs/metrics.md#scoring-external-transforms)",
     SetupScoreCommand});
}  // namespace

}  // namespace regbench::app
