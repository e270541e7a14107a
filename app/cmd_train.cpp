// `regbench train`: train a learned network (any registered family) on pairs made on the fly by a
// pair protocol (or read from a pair file), with validation, checkpoints and a wall-clock budget;
// and `--ablation` to train the paper's ablation variants. The data and the variants come from
// experiments/training.hpp.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "app/cli_numbers.hpp"
#include "app/commands.hpp"
#ifdef REGBENCH_HAVE_LEARNED
#include "baselines/learned.hpp"
#include "core/atomic_file.hpp"
#include "core/json_limits.hpp"
#include "core/output_rule.hpp"
#include "experiments/training.hpp"
#include "networks/family.hpp"
#include "networks/training/train.hpp"
#include "networks/zoo.hpp"
#endif

namespace regbench::app {
namespace {
#ifdef REGBENCH_HAVE_LEARNED

struct TrainArgs {
    std::string model;
    std::string config_file;
    std::string out;
    TrainingDataOptions data;  ///< its seed is --seed (train.seed)
    int batch = 0;
    int epochs = 0;
    int pairs_per_epoch = 0;
    double lr = 0.0;
    /// --resume, --minutes, --max-steps, --threads, --seed and --device bind straight to the
    /// trainer's options (their defaults live there); RunOne adds the per-run fields.
    networks::TrainOptions train;
    bool val_icp = true;
    std::string ablation;
    std::string bundle;  ///< --write-bundle FILE: write the data and config, train nothing
    bool list_models = false;  ///< --list-models: print the families' models and stop
    bool force = false;  ///< --force: replace an existing --write-bundle file
};

/// The command as given, for checkpoints' provenance.
std::string CommandLine(const CLI::App& cmd) {
    std::string line = "regbench train";
    for (const CLI::Option* o : cmd.get_options()) {
        if (o->count() == 0 || o->get_name() == "--help") continue;
        line += " " + o->get_name();
        for (const auto& r : o->results()) line += " " + r;
    }
    return line;
}

/// The --config file: depth-limited (a file nested 1M levels deep crashed the process with
/// SIGSEGV) and a JSON object (an array or a string was silently ignored and the run trained
/// on the named config alone). Throws naming the file.
nlohmann::json ReadJsonFile(const std::string& path) {
    const nlohmann::json j = ReadJsonFileBounded(path, "train: --config " + path);
    if (!j.is_object()) {
        throw std::runtime_error("train: --config " + path + " must hold a JSON object, got " +
                                 std::string(j.type_name()));
    }
    return j;
}

/// Named config + --config file + the command-line recipe flags.
nlohmann::json BuildConfig(const TrainArgs& a, const std::string& model,
                           const nlohmann::json& extra) {
    nlohmann::json overrides =
        a.config_file.empty() ? nlohmann::json::object() : ReadJsonFile(a.config_file);
    overrides.merge_patch(extra);
    nlohmann::json config = networks::ResolveConfig(model, overrides);
    if (a.batch > 0) config["train"]["batch"] = a.batch;
    if (a.epochs > 0) config["train"]["epochs"] = a.epochs;
    if (a.pairs_per_epoch > 0) config["train"]["pairs_per_epoch"] = a.pairs_per_epoch;
    if (a.lr > 0) config["train"]["lr"] = a.lr;
    return config;
}

void RunOne(const TrainArgs& a, const std::string& command_line, const nlohmann::json& config,
            const networks::TrainData& data, const std::string& out) {
    networks::TrainOptions o = a.train;
    o.out_dir = out;
    o.plan_to_budget = o.PlansToBudget(a.epochs > 0);
    o.run_info = {{"command", command_line}};
    if (a.val_icp) {
        o.refine = [](const PointCloud& s, const PointCloud& t, const Transform& init) {
            return IcpRefine(s, t, init);
        };
    }
    std::cerr << "train: " << config.value("name", std::string("?")) << " -> " << out << " ("
              << data.validation.size() << " validation pairs, " << a.train.threads << " threads, "
              << a.train.device << ")\n";
    const networks::TrainSummary s = networks::Train(config, data, o);
    std::cerr << "train: done, " << s.steps << " steps; checkpoints " << out << "/last, " << out
              << "/best\n";
}

/// --write-bundle: the shapes, protocol, seed and resolved config of this command in one file,
/// for regbench-train-portable on a machine with LibTorch alone (experiments/training_bundle.hpp).
void WriteBundle(const TrainArgs& a, const std::string& command_line) {
    if (!a.ablation.empty()) {
        throw std::invalid_argument("train: --write-bundle takes one --model, not --ablation");
    }
    // The file and the config are checked before the shapes are loaded (minutes on a real
    // dataset); the lock keeps a second writer off the file until it is renamed into place.
    const ClaimedOutput claim(a.bundle, {a.config_file, a.data.pairs_file}, OutputRule{a.force});
    const nlohmann::json config = BuildConfig(a, a.model, nlohmann::json::object());
    TrainingDataOptions data_options = a.data;
    data_options.seed = a.train.seed;
    TrainingBundle b = LoadTrainingBundle(data_options);
    b.config = config;
    b.command = command_line;
    b.length_given = a.epochs > 0;
    WriteTrainingBundle(a.bundle, b);
    std::cerr << "train: wrote " << a.bundle << " (" << b.train_shapes.size() << " training, "
              << b.val_shapes.size() << " validation shapes); train from it with "
              << "regbench-train-portable " << a.bundle << " --out DIR [--device cuda]\n";
}

/// The zoo's model names (networks/family.hpp), comma-separated.
std::string ModelList() {
    std::string list;
    for (const auto& m : networks::ModelNames()) list += (list.empty() ? "" : ", ") + m;
    return list;
}

/// --list-models: each network family (networks/family.hpp), its models and methods, and every
/// config key with each model's value and the key's doc.
void ListModels() {
    for (const auto& f : networks::Families()) {
        std::cout << f.arch << "  -  " << f.summary << "\n    models:";
        for (const auto& m : f.models) std::cout << " " << m;
        std::cout << "\n    methods:";
        for (const auto& m : f.methods) std::cout << " " << m.name;
        std::cout << "\n";
        for (const auto& [key, doc] : f.config_docs) {
            std::string values;
            for (const auto& m : f.models) {
                const nlohmann::json c = f.named_config(m);
                values += (values.empty() ? "" : " | ") +
                          (c.contains(key) ? c.at(key).dump() : std::string("-"));
            }
            std::cout << "    " << key << " = " << values << "    # " << doc << "\n";
        }
    }
}

void Run(const TrainArgs& a, const std::string& command_line) {
    if (a.list_models) {
        ListModels();
        return;
    }
    if (a.ablation.empty() && a.model.empty()) {
        throw std::invalid_argument("train: --model is required (known: " + ModelList() + ")");
    }
    // One writer per run directory (OUT.lock beside it), taken before the data are built: a
    // second train (or any regbench writer) on the same --out is refused naming the pid.
    if (!a.config_file.empty()) (void)ReadJsonFile(a.config_file);  // refused before any work
    if (!a.bundle.empty()) {
        WriteBundle(a, command_line);
        return;
    }
    if (a.out.empty()) throw std::invalid_argument("train: --out is required");
    // The one output rule (docs/usage.md, "Outputs"): an existing run folder is the trainer's
    // to judge (refused unless --resume), a link to another folder never followed.
    OutputRule rule;
    rule.folder = true;
    rule.continues = true;
    const ClaimedOutput claim(a.out, {a.config_file, a.data.pairs_file}, rule);
    TrainingDataOptions data_options = a.data;
    data_options.seed = a.train.seed;
    const networks::TrainData data = MakeTrainingData(data_options);
    if (a.ablation.empty()) {
        RunOne(a, command_line, BuildConfig(a, a.model, nlohmann::json::object()), data, a.out);
        return;
    }
    const LearnedVariants variants = AblationVariants(a.ablation);
    const std::string base = a.model.empty() ? variants.model : a.model;
    for (const auto& [variant, overrides] : variants.rows) {
        nlohmann::json config = BuildConfig(a, base, overrides);
        config["name"] = config.value("name", base);
        RunOne(a, command_line, config, data, (std::filesystem::path(a.out) / variant).string());
    }
}

void SetupTrainCommand(CLI::App* cmd) {
    auto a = std::make_shared<TrainArgs>();
    cmd->add_option("--model", a->model,
                    "Model: " + ModelList() + " (ablations: default the plan file's model)");
    cmd->add_flag("--list-models", a->list_models,
                  "Print every network family's models, methods and config keys (values per "
                  "model, one doc per key), then stop");
    cmd->add_option("--config", a->config_file, "JSON file merged over the named config");
    cmd->add_option("--out", a->out, "Run directory (checkpoints last/ best/, metrics.csv)");
    cmd->add_option("--protocol", a->data.protocol, "Pair protocol")->capture_default_str();
    cmd->add_option("--dataset", a->data.dataset,
                    "Dataset(s), comma-separated: cgal, procedural, PATH")
        ->capture_default_str();
    cmd->add_option("--split", a->data.split, "Training split")->capture_default_str();
    cmd->add_option("--val-split", a->data.val_split, "Validation split")->capture_default_str();
    cmd->add_option("--pairing", a->data.pairing, "shared | independent")->capture_default_str();
    cmd->add_flag("--jitter,!--no-jitter", a->data.jitter, "Jitter both clouds (default on)");
    cmd->add_option("--pairs-file", a->data.pairs_file, "Train on a frozen pair file instead");
    // Every number is checked before any work: a value that is NaN, negative or zero where
    // the recipe needs a positive one used to fall back to the full recipe silently.
    cmd->add_option("--val-fraction", a->data.val_fraction,
                    "Fraction of --pairs-file pairs held out for validation")
        ->check(OpenInterval(0.0, 1.0))
        ->capture_default_str();
    cmd->add_option("--val-pairs", a->data.val_pairs, "Validation pairs (protocol data)")
        ->check(PositiveWholeNumber())
        ->capture_default_str();
    cmd->add_option("--batch", a->batch, "Batch size (default: the model's recipe)")
        ->check(PositiveWholeNumber());
    cmd->add_option("--epochs", a->epochs, "Epochs (default: the model's recipe)")
        ->check(PositiveWholeNumber());
    cmd->add_option("--pairs-per-epoch", a->pairs_per_epoch, "Pairs per epoch (default: recipe)")
        ->check(PositiveWholeNumber());
    cmd->add_option("--lr", a->lr, "Learning rate in (0, 1] (default: recipe)")
        ->check(PositiveReal())
        ->check(ClosedInterval(0.0, networks::kMaxLearningRate));
    cmd->add_option("--minutes", a->train.minutes,
                    "Wall-clock budget of this invocation; ends with a validated checkpoint. On a "
                    "fresh run without --epochs/--max-steps the LR schedule is planned to fit it")
        ->check(PositiveReal());
    cmd->add_option("--max-steps", a->train.max_steps, "Stop after this many steps in total")
        ->check(PositiveWholeNumber());
    cmd->add_flag("--resume", a->train.resume, "Continue from OUT/last");
    cmd->add_option("--init-from", a->train.init_from,
                    "Start a fresh run from this checkpoint folder's weights (same model "
                    "config; fresh optimizer and LR plan), e.g. to fine-tune an object-trained "
                    "model on indoor scans")
        ->check(CLI::ExistingDirectory);
    cmd->add_option("--threads", a->train.threads, "Torch threads")
        ->check(ThreadCount())
        ->capture_default_str();
    cmd->add_option("--seed", a->train.seed, "Seed (weights, pairs, per-step randomness)")
        ->check(WholeNumber())
        ->capture_default_str();
    cmd->add_option("--device", a->train.device, "cpu | cuda")->capture_default_str();
    cmd->add_flag("!--no-val-icp", a->val_icp, "Skip the with-ICP validation metrics");
    cmd->add_option("--ablation", a->ablation,
                    "components | losses | clusters: train every variant into OUT/<variant>");
    cmd->add_option("--data-dir", a->data.data_dir, "Data directory for named datasets");
    cmd->add_option("--write-bundle", a->bundle,
                    "Write the training data and config to FILE for regbench-train-portable "
                    "(a machine with LibTorch alone, e.g. a GPU node) instead of training");
    cmd->add_flag("--force", a->force, "Replace an existing --write-bundle file");
    cmd->callback([cmd, a] { Run(*a, CommandLine(*cmd)); });
}

constexpr const char* kTrainSummary =
    "Train a learned registration network (every family of `regbench train --list-models`)";
#else
void SetupTrainCommand(CLI::App* cmd) {
    cmd->callback([] { throw std::runtime_error("train: this build has no LibTorch (networks/)"); });
}
constexpr const char* kTrainSummary = "Train a learned network (not in this build: needs LibTorch)";
#endif

[[maybe_unused]] const bool kTrainRegistered =
    RegisterCommand({"train", kTrainSummary, SetupTrainCommand});
}  // namespace

}  // namespace regbench::app
