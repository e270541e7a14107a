// `regbench train`: train a learned network (DeepGMR, OGMM) on pairs made on the fly by a pair
// protocol (or read from a pair file), with validation, checkpoints and a wall-clock budget; and
// `--ablation` to train the paper's ablation variants.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "app/cli_numbers.hpp"
#include "app/commands.hpp"
#ifdef REGBENCH_HAVE_LEARNED
#include "baselines/learned.hpp"
#include "core/file_lock.hpp"
#include "core/json_limits.hpp"
#include "datasets/dataset_shapes.hpp"
#include "ogmm/train.hpp"
#include "ogmm/zoo.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_protocols.hpp"
#endif

namespace regbench::app {
namespace {
#ifdef REGBENCH_HAVE_LEARNED

struct TrainArgs {
    std::string model;
    std::string config_file;
    std::string out;
    std::string protocol = "partial";
    std::string dataset = "cgal,procedural";
    std::string split = "train";
    std::string val_split = "val";
    std::string pairing = "shared";
    bool jitter = true;
    std::string pairs_file;
    double val_fraction = 0.2;
    int val_pairs = 200;
    int batch = 0;
    int epochs = 0;
    int pairs_per_epoch = 0;
    double lr = 0.0;
    /// --resume, --minutes, --max-steps, --threads, --seed and --device bind straight to the
    /// trainer's options (their defaults live there); RunOne adds the per-run fields.
    ogmm::TrainOptions train;
    bool val_icp = true;
    std::string ablation;
    std::string data_dir;
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

std::vector<std::string> SplitList(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream in(s);
    for (std::string item; std::getline(in, item, ',');) {
        if (!item.empty()) out.push_back(item);
    }
    return out;
}

ogmm::TrainSample ToSample(const Pair& p) {
    ogmm::TrainSample s;
    s.source = p.source;
    s.target = p.target;
    s.T_gt = p.T_gt;
    s.source_overlap = p.source_overlap.cast<double>();
    s.target_overlap = p.target_overlap.cast<double>();
    return s;
}

/// Shapes of every dataset in the comma-separated list, for one split.
std::vector<ShapeSource> LoadShapes(const TrainArgs& a, const std::string& split) {
    DatasetOptions options;
    options.data_dir = a.data_dir;
    const ShapeLoader load = DatasetShapeLoader(options);
    std::vector<ShapeSource> shapes;
    for (const auto& name : SplitList(a.dataset)) {
        auto part = load(name, split);
        shapes.insert(shapes.end(), part.begin(), part.end());
    }
    if (shapes.empty()) {
        throw std::runtime_error("train: dataset '" + a.dataset + "' split '" + split +
                                 "' holds no shapes");
    }
    return shapes;
}

/// Training stream and validation pairs from a protocol over datasets, or from a pair file.
ogmm::TrainData MakeData(const TrainArgs& a) {
    ogmm::TrainData data;
    if (!a.pairs_file.empty()) {
        auto set = std::make_shared<PairSet>(ReadPairFile(a.pairs_file));
        const std::size_t n = set->pairs.size();
        const auto n_val = static_cast<std::size_t>(a.val_fraction * static_cast<double>(n));
        if (n_val < 1 || n_val >= n) {
            throw std::invalid_argument("train: pair file " + a.pairs_file + " has " +
                                        std::to_string(n) + " pairs; --val-fraction " +
                                        std::to_string(a.val_fraction) +
                                        " leaves no training or no validation pair");
        }
        const std::size_t n_train = n - n_val;  // the last n_val pairs validate
        for (std::size_t i = n_train; i < n; ++i)
            data.validation.push_back(ToSample(set->pairs[i]));
        data.train_pair = [set, n_train](std::uint64_t k) {
            return ToSample(set->pairs[k % n_train]);
        };
        data.provenance = {{"pairs_file", a.pairs_file},
                           {"pairs_file_provenance", set->provenance},
                           {"train_pairs", n_train},
                           {"val_pairs", n_val}};
        return data;
    }
    Protocol protocol = ParseProtocol(a.protocol);
    if (a.jitter && protocol == Protocol::kPartial) protocol = Protocol::kJitter;
    ProtocolOptions options = DefaultProtocolOptions(protocol);
    options.pairing = ParsePairing(a.pairing);
    ValidateProtocolOptions(options);
    auto train_shapes = std::make_shared<std::vector<ShapeSource>>(LoadShapes(a, a.split));
    const std::vector<ShapeSource> val_shapes = LoadShapes(a, a.val_split);
    // Validation pairs come from another seed stream than training pairs.
    const std::uint64_t val_seed = a.train.seed ^ 0x76616c6964ULL;
    for (int i = 0; i < a.val_pairs; ++i) {
        data.validation.push_back(ToSample(GeneratePair(val_shapes, options, val_seed, i)));
    }
    const std::uint64_t seed = a.train.seed;
    data.train_pair = [train_shapes, options, seed](std::uint64_t k) {
        return ToSample(GeneratePair(*train_shapes, options, seed, k));
    };
    data.provenance = {{"protocol", ProtocolProvenance(options)},
                       {"dataset", a.dataset},
                       {"split", a.split},
                       {"val_split", a.val_split},
                       {"train_shapes", train_shapes->size()},
                       {"val_shapes", val_shapes.size()},
                       {"val_pairs", a.val_pairs},
                       {"seed", a.train.seed},
                       {"val_seed", val_seed}};
    return data;
}

/// The --config file: depth-limited (a file nested 1M levels deep crashed the process with
/// SIGSEGV) and a JSON object (an array or a string was silently ignored and the run trained
/// on the named config alone). Throws naming the file.
nlohmann::json ReadJsonFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("train: cannot open --config " + path);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    nlohmann::json j;
    try {
        j = ParseJsonBounded(text, "--config " + path);
    } catch (const std::exception& e) {
        throw std::runtime_error("train: --config " + path + " is not valid JSON: " + e.what());
    }
    if (!j.is_object()) {
        throw std::runtime_error("train: --config " + path + " must hold a JSON object, got " +
                                 std::string(j.type_name()));
    }
    return j;
}

/// Named config + --config file + the command-line recipe flags.
nlohmann::json BuildConfig(const TrainArgs& a,
                           const std::string& model,
                           const nlohmann::json& extra) {
    nlohmann::json overrides =
        a.config_file.empty() ? nlohmann::json::object() : ReadJsonFile(a.config_file);
    overrides.merge_patch(extra);
    nlohmann::json config = ogmm::ResolveConfig(model, overrides);
    if (a.batch > 0) config["train"]["batch"] = a.batch;
    if (a.epochs > 0) config["train"]["epochs"] = a.epochs;
    if (a.pairs_per_epoch > 0) config["train"]["pairs_per_epoch"] = a.pairs_per_epoch;
    if (a.lr > 0) config["train"]["lr"] = a.lr;
    return config;
}

/// Variants of the paper's ablation tables (config overrides of the small OGMM config).
std::vector<std::pair<std::string, nlohmann::json>> AblationVariants(const std::string& which) {
    if (which == "components") {  // Tab. 4; variant names are the paper's row names
        return {{"full", nlohmann::json::object()},
                {"no_SPE", {{"spe", false}}},
                {"no_CSA", {{"csa", false}}},
                {"no_OSP", {{"osp", false}}}};
    }
    if (which == "losses") {  // Tab. 5: GR = 10 L_pose + 0.01 L_W, CL = NT-Xent, OS = overlap MSE
        std::vector<std::pair<std::string, nlohmann::json>> v;
        for (const auto& [name, gr, cl, os] :
             std::vector<std::tuple<std::string, bool, bool, bool>>{
                 {"GR", true, false, false},
                 {"CL", false, true, false},
                 {"OS", false, false, true},
                 {"GR+CL", true, true, false},
                 {"CL+OS", false, true, true},
                 {"GR+OS", true, false, true},
                 {"GR+CL+OS", true, true, true}}) {
            v.push_back({name,
                         {{"w_pose", gr ? 10.0 : 0.0},
                          {"w_welsch", gr ? 0.01 : 0.0},
                          {"w_clu", cl ? 1.0 : 0.0},
                          {"w_ovl", os ? 1.0 : 0.0}}});
        }
        return v;
    }
    if (which == "clusters") {  // supplementary cluster-count table
        std::vector<std::pair<std::string, nlohmann::json>> v;
        for (int j : {8, 16, 32, 48, 64}) v.push_back({"J" + std::to_string(j), {{"clusters", j}}});
        return v;
    }
    throw std::invalid_argument("--ablation must be components, losses or clusters, got '" + which +
                                "'");
}

void RunOne(const TrainArgs& a,
            const std::string& command_line,
            const nlohmann::json& config,
            const ogmm::TrainData& data,
            const std::string& out) {
    ogmm::TrainOptions o = a.train;
    o.out_dir = out;
    // A budget without an explicit length plans the LR schedule to what fits the budget.
    o.plan_to_budget = a.train.minutes > 0 && !a.train.resume && a.epochs == 0 &&
                       a.train.max_steps == 0;
    o.run_info = {{"command", command_line}};
    if (a.val_icp) {
        o.refine = [](const PointCloud& s, const PointCloud& t, const Transform& init) {
            return IcpRefine(s, t, init);
        };
    }
    std::cerr << "train: " << config.value("name", std::string("?")) << " -> " << out << " ("
              << data.validation.size() << " validation pairs, " << a.train.threads << " threads, "
              << a.train.device << ")\n";
    const ogmm::TrainSummary s = ogmm::Train(config, data, o);
    std::cerr << "train: done, " << s.steps << " steps; checkpoints " << out << "/last, " << out
              << "/best\n";
}

void Run(const TrainArgs& a, const std::string& command_line) {
    if (a.ablation.empty() && a.model.empty()) {
        throw std::invalid_argument(
            "train: --model is required (known: deepgmr, deepgmr-small, "
            "deepgmr-orig, deepgmr-orig-xyz, ogmm, ogmm-small, ogmm-tiny)");
    }
    // One writer per run directory (OUT.lock beside it), taken before the data are built: a
    // second train (or any regbench writer) on the same --out is refused naming the pid.
    if (!a.config_file.empty()) (void)ReadJsonFile(a.config_file);  // refused before any work
    const OutputLock lock(a.out);
    const ogmm::TrainData data = MakeData(a);
    if (a.ablation.empty()) {
        RunOne(a, command_line, BuildConfig(a, a.model, nlohmann::json::object()), data, a.out);
        return;
    }
    const std::string base = a.model.empty() ? "ogmm-small" : a.model;
    for (const auto& [variant, overrides] : AblationVariants(a.ablation)) {
        nlohmann::json config = BuildConfig(a, base, overrides);
        config["name"] = config.value("name", base);
        RunOne(a, command_line, config, data, (std::filesystem::path(a.out) / variant).string());
    }
}

void SetupTrainCommand(CLI::App* cmd) {
    auto a = std::make_shared<TrainArgs>();
    cmd->add_option("--model", a->model,
                    "Model: deepgmr, deepgmr-small, deepgmr-orig, deepgmr-orig-xyz, ogmm, "
                    "ogmm-small, ogmm-tiny (ablations: default ogmm-small)");
    cmd->add_option("--config", a->config_file, "JSON file merged over the named config");
    cmd->add_option("--out", a->out, "Run directory (checkpoints last/ best/, metrics.csv)")
        ->required();
    cmd->add_option("--protocol", a->protocol, "Pair protocol")->capture_default_str();
    cmd->add_option("--dataset", a->dataset, "Dataset(s), comma-separated: cgal, procedural, PATH")
        ->capture_default_str();
    cmd->add_option("--split", a->split, "Training split")->capture_default_str();
    cmd->add_option("--val-split", a->val_split, "Validation split")->capture_default_str();
    cmd->add_option("--pairing", a->pairing, "shared | independent")->capture_default_str();
    cmd->add_flag("--jitter,!--no-jitter", a->jitter, "Jitter both clouds (default on)");
    cmd->add_option("--pairs-file", a->pairs_file, "Train on a frozen pair file instead");
    // Every number is checked before any work: a value that is NaN, negative or zero where
    // the recipe needs a positive one used to fall back to the full recipe silently.
    cmd->add_option("--val-fraction", a->val_fraction,
                    "Fraction of --pairs-file pairs held out for validation")
        ->check(OpenInterval(0.0, 1.0))
        ->capture_default_str();
    cmd->add_option("--val-pairs", a->val_pairs, "Validation pairs (protocol data)")
        ->check(PositiveWholeNumber())
        ->capture_default_str();
    cmd->add_option("--batch", a->batch, "Batch size (default: the model's recipe)")
        ->check(PositiveWholeNumber());
    cmd->add_option("--epochs", a->epochs, "Epochs (default: the model's recipe)")
        ->check(PositiveWholeNumber());
    cmd->add_option("--pairs-per-epoch", a->pairs_per_epoch, "Pairs per epoch (default: recipe)")
        ->check(PositiveWholeNumber());
    cmd->add_option("--lr", a->lr, "Learning rate (default: recipe)")->check(PositiveReal());
    cmd->add_option("--minutes", a->train.minutes,
                    "Wall-clock budget of this invocation; ends with a validated checkpoint. On a "
                    "fresh run without --epochs/--max-steps the LR schedule is planned to fit it")
        ->check(PositiveReal());
    cmd->add_option("--max-steps", a->train.max_steps, "Stop after this many steps in total")
        ->check(PositiveWholeNumber());
    cmd->add_flag("--resume", a->train.resume, "Continue from OUT/last");
    cmd->add_option("--threads", a->train.threads, "Torch threads")
        ->check(PositiveWholeNumber())
        ->capture_default_str();
    cmd->add_option("--seed", a->train.seed, "Seed (weights, pairs, per-step randomness)")
        ->check(WholeNumber())
        ->capture_default_str();
    cmd->add_option("--device", a->train.device, "cpu | cuda")->capture_default_str();
    cmd->add_flag("!--no-val-icp", a->val_icp, "Skip the with-ICP validation metrics");
    cmd->add_option("--ablation", a->ablation,
                    "components | losses | clusters: train every variant into OUT/<variant>");
    cmd->add_option("--data-dir", a->data_dir, "Data directory for named datasets");
    cmd->callback([cmd, a] { Run(*a, CommandLine(*cmd)); });
}

constexpr const char* kTrainSummary = "Train a learned registration network (DeepGMR, OGMM)";
#else
void SetupTrainCommand(CLI::App* cmd) {
    cmd->callback([] { throw std::runtime_error("train: this build has no LibTorch (ogmm/)"); });
}
constexpr const char* kTrainSummary = "Train a learned network (not in this build: needs LibTorch)";
#endif

[[maybe_unused]] const bool kTrainRegistered =
    RegisterCommand({"train", kTrainSummary, SetupTrainCommand});
}  // namespace

}  // namespace regbench::app
