// `regbench generate`: freeze pairs of one protocol into an HDF5 benchmark file.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "app/cli_numbers.hpp"
#include "app/cli_params.hpp"
#include "app/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/output_rule.hpp"
#include "core/sha256.hpp"
#include "core/version.hpp"
#include "datasets/dataset.hpp"
#include "datasets/dataset_shapes.hpp"
#include "protocols/generate.hpp"
#include "runners/progress.hpp"

namespace regbench::app {
namespace {

struct GenerateArgs {
    std::string protocol = "partial";
    std::string data_dir;
    GenerateRequest request;
    ProtocolOptions flags;  ///< values of the protocol flags (applied only when given)
    std::string motion = "euler";
    std::string pairing = "independent";
    std::string pairs;  ///< a whole number, or "all" (one pair per item of the split)
    bool force = false;
};

/// Protocol defaults, overridden by every protocol flag the user gave.
ProtocolOptions BuildOptions(const CLI::App& cmd, const GenerateArgs& a) {
    ProtocolOptions o = DefaultProtocolOptions(ParseProtocol(a.protocol));
    const auto given = [&](const char* flag) { return cmd.get_option(flag)->count() > 0; };
    if (given("--points")) o.points = a.flags.points;
    if (given("--keep")) o.keep = a.flags.keep;
    if (given("--noise-sigma")) o.noise_sigma = a.flags.noise_sigma;
    if (given("--noise-clip")) o.noise_clip = a.flags.noise_clip;
    if (given("--motion")) o.motion = ParseMotionConvention(a.motion);
    if (given("--max-rotation-deg")) o.max_rotation_deg = a.flags.max_rotation_deg;
    if (given("--max-translation")) o.max_translation = a.flags.max_translation;
    if (given("--pairing")) o.pairing = ParsePairing(a.pairing);
    if (given("--eta")) o.eta = a.flags.eta;
    if (given("--density-keep")) o.density_keep = a.flags.density_keep;
    if (given("--sweep-keeps")) o.sweep_keeps = a.flags.sweep_keeps;
    return o;
}

/// Progress on stderr with rate and ETA (the same meter `run` uses), created on the first call
/// because only then is the total known.
ProgressCallback MakeProgress() {
    auto meter = std::make_shared<std::unique_ptr<ProgressMeter>>();
    return [meter](std::size_t done, std::size_t total) {
        if (!*meter) *meter = std::make_unique<ProgressMeter>("generate", total);
        (*meter)->Advance();
        if (done == total) (*meter)->Finish();
    };
}

/// Wraps the loader to warn when the indoor protocol (depth scans of rooms) is asked of object
/// meshes: it runs, but the pairs are not what the paper's Tab. 3 measured; and to say so when
/// --pairs asks for more pairs than the split has items (per overlap level): items are reused.
ShapeLoader WarnOnLoad(ShapeLoader loader, const GenerateRequest& request) {
    const Protocol protocol = request.options.protocol;
    const std::size_t levels = ProtocolLevels(request.options);
    const std::size_t pairs = request.one_per_item ? 0 : request.num_pairs;
    return [=](const std::string& dataset, const std::string& split) {
        std::vector<ShapeSource> shapes = loader(dataset, split);
        const std::size_t distinct = shapes.size() * levels;
        if (!shapes.empty() && pairs > distinct) {
            std::cerr << "generate: note: --pairs " << pairs << " is more than the "
                      << shapes.size() << " items of '" << dataset << "' split '" << split << "'"
                      << (levels > 1 ? " times " + std::to_string(levels) + " levels" : "")
                      << ", so it reuses items: pair k uses item (k / " << levels << ") mod "
                      << shapes.size() << " with its own crop, noise and motion (--pairs all "
                      << "makes one pair per item)\n";
        }
        const bool meshes = std::any_of(shapes.begin(), shapes.end(),
                                        [](const ShapeSource& s) { return s.is_mesh(); });
        if (protocol == Protocol::kIndoor && meshes) {
            std::cerr << "generate: warning: --protocol indoor on '" << dataset
                      << "', which holds object meshes; the paper's indoor protocol resamples "
                         "scans of rooms (7Scenes, ICL-NUIM; --dataset indoor-sim for simulated "
                         "ones)\n";
        }
        return shapes;
    };
}

/// The dataset given as a path (a file, or a folder of point files): an input --out may not be
/// nor lie inside (`--dataset plyd --out plyd/0000_src.ply` replaced that input, exit 0).
std::vector<std::string> DatasetInputs(const std::string& datasets) {
    std::vector<std::string> inputs;
    std::stringstream list(datasets);
    for (std::string item; std::getline(list, item, ',');) inputs.push_back(item);
    return inputs;
}

void SetupGenerateCommand(CLI::App* cmd) {
    auto a = std::make_shared<GenerateArgs>();
    std::string protocols;
    for (const auto& p : ProtocolNames()) protocols += (protocols.empty() ? "" : ", ") + p;
    cmd->add_option("--protocol", a->protocol, "Pair protocol: " + protocols)
        ->check(ParsedBy(ParseProtocol, "PROTOCOL"))
        ->capture_default_str();
    cmd->add_option("--dataset", a->request.dataset, "Dataset name or path (see docs/datasets.md)")
        ->capture_default_str();
    cmd->add_option(
        "--split", a->request.split,
        "Dataset split (default: test; all for a single file or a folder of point files)")
        ->check(ParsedBy(CheckSplitName, "SPLIT"));
    cmd->add_option("--data-dir", a->data_dir,
                    "Data directory for named datasets (default: ./data)");
    cmd->add_option("--pairs", a->pairs,
                    "Number of pairs (pair k uses item k mod items), or 'all': one pair per item "
                    "of the split (per overlap-sweep level)")
        ->required()
        ->check(WholeNumber() | CLI::IsMember({"all"}));
    cmd->add_option("--seed", a->request.seed, "Benchmark seed")
        ->capture_default_str()
        ->check(WholeNumber());
    cmd->add_option("--out", a->request.out, "Output HDF5 file")->required();
    cmd->add_flag("--force", a->force, "Replace an existing --out");
    cmd->add_option("--points", a->flags.points, "Points sampled per cloud (1024; indoor 2048)")
        ->check(WholeNumber());
    // Every number is checked as text (an empty value, nan, inf, 1e400 are usage errors: an
    // unset shell variable read as 0 made a benchmark without rotation), then its range by
    // CheckGenerateRequest before any work.
    cmd->add_option("--keep", a->flags.keep, "Crop keep ratio in (0, 1] (0.7)")
        ->check(PositiveReal());
    cmd->add_option("--noise-sigma", a->flags.noise_sigma, "Jitter sigma (0.01)")
        ->check(NonNegativeReal());
    cmd->add_option("--noise-clip", a->flags.noise_clip, "Jitter clip (0.05)")
        ->check(NonNegativeReal());
    cmd->add_option("--motion", a->motion, "Motion convention: euler | axis-angle (euler)")
        ->check(ParsedBy(ParseMotionConvention, "MOTION"));
    cmd->add_option("--max-rotation-deg", a->flags.max_rotation_deg, "Max rotation [deg] (45)")
        ->check(NonNegativeReal());
    cmd->add_option("--max-translation", a->flags.max_translation, "Max translation (0.5)")
        ->check(NonNegativeReal());
    cmd->add_option("--pairing", a->pairing,
                    "Pairing: independent | shared | stored (the file's own source/target/"
                    "transform, e.g. ICL-NUIM test) (independent)")
        ->check(ParsedBy(ParsePairing, "PAIRING"));
    cmd->add_option("--scale", a->request.scale,
                    "The data's size over the paper's unit-sphere objects (e.g. 150 for objects "
                    "of radius 150 mm): --max-translation, --noise-sigma, --noise-clip and --eta "
                    "are multiplied by it; generate refuses clouds whose radius is more than 10 "
                    "times off it (1)")
        ->check(PositiveReal());
    cmd->add_option("--eta", a->flags.eta, "Overlap label radius (0.1)")->check(PositiveReal());
    cmd->add_option("--density-keep", a->flags.density_keep, "density: distinct fraction (0.5)")
        ->check(PositiveReal());
    cmd->add_option("--sweep-keeps", a->flags.sweep_keeps, "overlap-sweep: crop keep ratios")
        ->delimiter(',')
        ->check(PositiveReal());
    cmd->callback([cmd, a] {
        GenerateRequest request = a->request;
        request.options = BuildOptions(*cmd, *a);
        request.one_per_item = a->pairs == "all";
        if (!request.one_per_item) request.num_pairs = std::stoull(a->pairs);  // validated digits
        try {
            CheckGenerateRequest(request);  // every number's range: a usage error, before work
        } catch (const std::invalid_argument& e) {
            throw CLI::ValidationError(e.what());
        }
        // The one output rule (docs/usage.md, "Outputs"), then one writer per --out.
        OutputRule rule;
        rule.replace = a->force;
        const ClaimedOutput claim(request.out, DatasetInputs(request.dataset), rule);
        if (cmd->get_option("--split")->count() == 0) {
            request.split = DefaultSplit(request.dataset);
        }
        request.extra_provenance = {{"regbench_version", RegbenchVersion()},
                                    {"git_sha", RegbenchGitSha()}};
        // A dataset given as one file (DeepGMR's test .h5, a ModelNet40 .h5): its content hash
        // goes into the pair file and every report caption.
        if (std::filesystem::is_regular_file(request.dataset)) {
            request.extra_provenance["dataset_sha256"] = Sha256File(request.dataset);
        }
        DatasetOptions dataset_options;
        dataset_options.data_dir = a->data_dir;
        GenerateToFile(request, WarnOnLoad(DatasetShapeLoader(dataset_options), request),
                       MakeProgress());
        std::cerr << "generate: wrote " << request.out << "\n";
    });
}

[[maybe_unused]] const bool kGenerateRegistered = RegisterCommand(
    {"generate", "Generate a frozen benchmark of registration pairs", SetupGenerateCommand});
}  // namespace

}  // namespace regbench::app
