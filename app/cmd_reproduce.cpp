// `regbench reproduce`: every paper table from one command, into one folder.
#include <iostream>

#include "app/cli_numbers.hpp"
#include "app/commands.hpp"
#include "core/output_rule.hpp"
#include "experiments/reproduce.hpp"

namespace regbench::app {

namespace {

void SetupReproduceCommand(CLI::App* cmd) {
    auto o = std::make_shared<ReproduceOptions>();
    std::string tables;
    for (const auto& t : ReproducibleTables()) tables += (tables.empty() ? "" : ", ") + t;
    cmd->add_flag("--quick", o->quick,
                  "Smoke run of every table: 10 pairs per experiment (5 per indoor set, 2 per "
                  "overlap level), learned methods without their -noicp variants");
    cmd->add_option("--tables", o->tables, "Tables (ids or prefixes, e.g. table1,supp): " + tables)
        ->delimiter(',');
    cmd->add_option("--experiment", o->experiment_files,
                    "Experiment file (JSON, docs/reproducing.md) run instead of the paper's "
                    "plan; repeatable")
        ->check(CLI::ExistingFile);
    cmd->add_option("--modelnet40", o->modelnet40,
                    "ModelNet40 root (OFF tree or modelnet40_ply_hdf5_2048); default: the "
                    "embedded mesh corpus, and every table says so");
    cmd->add_option("--7scenes", o->sevenscenes, "7Scenes root; default: simulated indoor scans");
    cmd->add_option("--icl-nuim", o->icl_nuim, "ICL-NUIM root; default: simulated indoor scans");
    cmd->add_option("--out", o->out_dir, "Report folder (a second invocation continues it)")
        ->capture_default_str();
    cmd->add_option("--data-dir", o->data_dir, "Data directory of the embedded corpus");
    cmd->add_option("--jobs", o->jobs, "Pairs run in parallel")
        ->check(PositiveWholeNumber())
        ->capture_default_str();
    cmd->add_option("--timeout", o->timeout_seconds,
                    "Seconds per call, each in a child process (0: in-process)")
        ->check(NonNegativeReal())
        ->capture_default_str();
    cmd->add_option("--pairs", o->pairs,
                    "Pairs per experiment (default: 10 with --quick; else 1000 on the fallbacks, "
                    "one per test item on real data)")
        ->check(PositiveWholeNumber());  // 0 used to mean "the default" silently
    cmd->add_option("--seed", o->seed, "Benchmark seed")
        ->check(WholeNumber())
        ->capture_default_str();
    cmd->add_option("--methods", o->methods, "Methods (default: every registered one)")
        ->delimiter(',');
    cmd->add_option("--weights", o->weights,
                    "Weights manifest (JSON): the checkpoint each learned method runs per "
                    "experiment, regbench folders or the authors' .pth files (imported into "
                    "OUT/weights); default: the shipped data/models/weights.json "
                    "(docs/reproducing.md)")
        ->check(CLI::ExistingFile);
    // The steps of a run shared by several machines or a Slurm array (docs/cluster.md, "The
    // paper's tables on a cluster"; scripts/slurm/regbench-reproduce.sbatch submits them).
    auto shard = std::make_shared<std::string>();
    auto prepare = cmd->add_flag(
        "--prepare",
        "Shared run, step 1 (once): generate every pair file into --out and record the options");
    auto shard_opt = cmd->add_option(
        "--shard", *shard,
        "Shared run, step 2: run shard i of n (pairs k with k % n == i) of every experiment's "
        "calls into OUT/shards/<i>-of-<n>/, resumable; given as i/n");
    auto render = cmd->add_flag("--render",
                                "Shared run, step 3: merge the shards into OUT/results/ (every "
                                "experiment, pair and method exactly once) and write the reports");
    prepare->excludes(shard_opt)->excludes(render);
    shard_opt->excludes(render);
    cmd->callback([o, shard, prepare, shard_opt, render] {
        if (*prepare) o->step = ReproduceOptions::Step::kPrepare;
        if (*render) o->step = ReproduceOptions::Step::kRender;
        if (*shard_opt) {
            o->step = ReproduceOptions::Step::kShard;
            ParseShard(*shard, &o->shard_index, &o->shard_count);
        }
        // The one output rule (docs/usage.md, "Outputs"): the folder may exist (a second
        // invocation continues it) but is never a link to another folder nor inside an input.
        OutputRule rule;
        rule.folder = true;
        rule.continues = true;
        std::vector<std::string> inputs = o->experiment_files;
        if (!o->weights.empty()) inputs.push_back(o->weights);
        for (const std::string* root : {&o->modelnet40, &o->sevenscenes, &o->icl_nuim}) {
            inputs.push_back(*root);
        }
        CheckOutputRule(o->out_dir, inputs, rule);
        const ReproduceSummary s = Reproduce(*o, std::cerr);
        if (o->step == ReproduceOptions::Step::kPrepare) {
            std::cout << "pairs:         " << s.out_dir << "/pairs\n";
            return;
        }
        if (o->step == ReproduceOptions::Step::kShard) {
            std::cout << "shard results: " << s.shard_dir << "\n";
            return;
        }
        std::cout << "report folder: " << s.out_dir << "\n"
                  << "tables:        " << s.markdown_path << "\n"
                  << "HTML report:   " << s.html_path << "\n";
    });
}

[[maybe_unused]] const bool kReproduceRegistered = RegisterCommand(
    {"reproduce",
     "Generate the pairs of the paper's tables, run the methods (isolated, resumable) and "
     "write every report (Markdown, LaTeX, CSV, JSON, HTML) into one folder",
     SetupReproduceCommand});
}  // namespace

}  // namespace regbench::app
