// `regbench run`: run methods over a frozen pair file, one JSONL row per pair and method.
#include <fmt/format.h>

#include <iostream>
#include <stdexcept>

#include "app/cli_numbers.hpp"
#include "app/cli_params.hpp"
#include "app/commands.hpp"
#include "core/cpu_time.hpp"
#include "core/output_rule.hpp"
#include "runners/runner.hpp"

namespace regbench::app {

namespace {

void SetupRunCommand(CLI::App* cmd) {
    auto opts = std::make_shared<RunOptions>();
    auto m = std::make_shared<MethodArgs>();
    auto shard = std::make_shared<std::string>("0/1");
    auto quiet = std::make_shared<bool>(false);
    auto euler = std::make_shared<std::string>("zyx");
    auto force = std::make_shared<bool>(false);
    cmd->add_option("--pairs", opts->pairs_path, "Frozen HDF5 pair file (regbench generate/import)")
        ->required();
    m->Add(cmd, "Comma-separated method names (see `regbench methods`)",
           "JSON object of parameters per method, e.g. '{\"cpd\": {\"w\": 0.1}}'");
    // align's and score's spelling, a common slip here: refused naming the right flag
    // (hidden from --help; a validator, so it is reported before "--methods is required").
    cmd->add_option("--method")
        ->group("")
        ->check(CLI::Validator(
            [](std::string&) -> std::string {
                return "run takes --methods NAME[,NAME...] (comma-separated), not --method; did "
                       "you mean --methods?";
            },
            ""));
    cmd->add_option("--out", opts->out_path,
                    "Output JSONL (written as OUT.part, renamed at the end)")
        ->required();
    cmd->add_option("--jobs,-j", opts->jobs, "Pairs processed in parallel")
        ->check(PositiveWholeNumber());
    cmd->add_option(
           "--threads", opts->threads_per_call,
           "OpenMP threads inside one method call (timings are single-threaded by default)")
        ->check(ThreadCount());
    cmd->add_flag("--resume", opts->resume,
                  "Keep rows of an interrupted or finished run (OUT.part, else OUT) and skip "
                  "them");
    cmd->add_flag("--force", *force,
                  "Replace an existing OUT (without --resume or --force an existing OUT is "
                  "refused and left untouched)");
    cmd->add_option("--shard", *shard,
                    "Process pairs k with k % n == i, given as i/n (Slurm arrays)");
    cmd->add_option("--timeout", opts->timeout_seconds,
                    "Seconds per call; > 0 runs each call in a child process (isolates crashes)")
        ->check(NonNegativeReal());
    cmd->add_option("--max-points", opts->max_points,
                    "Scale guard: calls that stay O(N*M) at scale (cpd e_step dense, gmmreg/svr "
                    "kernel_sums dense; their defaults approximate) on clouds above this many "
                    "points are refused, or downsampled with --downsample; 0 = no guard")
        ->check(WholeNumber())
        ->capture_default_str();
    cmd->add_flag("--downsample", opts->downsample,
                  "Scale guard: run such calls on clouds reduced to --max-points points by an "
                  "evenly spaced stride (recorded in each row as \"downsampled\")");
    cmd->add_option("--euler", *euler,
                    "Euler angles of mae_r/rmse_r: zyx = scipy as_euler('zyx'), the paper's; "
                    "xyz = RPMNet's (docs/metrics.md)")
        ->check(CLI::IsMember({"zyx", "xyz"}))
        ->capture_default_str();
    AddMetricOptions(cmd, &opts->metric_options);
    cmd->add_flag("--quiet,-q", *quiet, "No progress line");
    cmd->callback([=] {
        RunOptions o = *opts;
        o.ccd_clip_given = cmd->count("--ccd-clip") > 0;
        if (o.resume && *force) {
            throw CLI::ValidationError("--resume and --force exclude each other");
        }
        // The one output rule (docs/usage.md, "Outputs"): a finished result file (often a
        // baseline) is never replaced by accident, nor the pair file, nor through a link.
        OutputRule rule;
        rule.replace = o.resume || *force;
        rule.how_to_replace = "pass --resume to continue it or --force to replace it";
        CheckOutputRule(o.out_path, {o.pairs_path}, rule);
        o.methods = m->Specs();
        ParseShard(*shard, &o.shard_index, &o.shard_count);
        o.progress = !*quiet;
        o.euler = ParseEulerConvention(*euler);
        // Threads beyond the idle cores wait for each other: wall time balloons and the
        // per-call timings stop meaning anything (docs/performance.md).
        const MachineLoad load = ReadMachineLoad();
        if (o.threads_per_call > 1 && o.threads_per_call > load.FreeCores()) {
            std::cerr << fmt::format(
                "[run] warning: --threads {} exceeds the {} free core(s) ({} cores, 1-min load "
                "{:.1f}); expect wall times far above CPU times\n",
                o.threads_per_call, load.FreeCores(), load.cores, load.load1);
        }
        const RunSummary s = RunBenchmark(o);
        std::cerr << fmt::format("[run] wrote {} rows ({} resumed, {} failed) to {} in {:.1f} s\n",
                                 s.rows_written, s.rows_skipped, s.failures, o.out_path,
                                 s.wall_seconds);
    });
}

[[maybe_unused]] const bool kRunRegistered = RegisterCommand(
    {"run", "Run methods over a pair file and write JSONL results", SetupRunCommand});
}  // namespace

}  // namespace regbench::app
