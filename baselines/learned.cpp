// The learned methods. Neither LibTorch nor Open3D headers are included here: the networks are
// reached through networks/ (networks/inference.hpp), ICP through the `icp` method (baselines/icp.cpp).
#include "baselines/learned.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <mutex>

#include "baselines/icp.hpp"
#include "core/cpu_time.hpp"
#include "core/data_dir.hpp"
#include "core/params.hpp"
#include "core/sha256.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/cost.hpp"
#include "networks/family.hpp"
#include "networks/gemm_floor.hpp"
#include "networks/inference.hpp"

namespace regbench {

std::string ShippedCheckpointDir(const std::string& name) {
    if (const char* env = std::getenv("REGBENCH_MODELS"); env != nullptr && *env != '\0') {
        return (std::filesystem::path(env) / name).string();
    }
    return (std::filesystem::path(DataDir()) / "models" / name).string();
}

Transform IcpRefine(const PointCloud& source, const PointCloud& target, const Transform& initial,
                    const IcpRefineOptions& options, AlignResult* details) {
    const auto icp = IcpMethodInfo().create(
        {{"max_correspondence_distance", options.max_correspondence_distance},
         {"max_iterations", options.max_iterations},
         {"relative_fitness", options.relative_fitness},
         {"relative_rmse", options.relative_rmse}});
    // Open3D's RegistrationICP from `initial` first moves the source by it; doing that here and
    // starting from the identity is the same computation.
    const PointCloud moved = ((source * initial.topLeftCorner<3, 3>().transpose()).rowwise() +
                              initial.topRightCorner<3, 1>().transpose());
    const AlignResult r = icp->Align(moved, target);
    if (details != nullptr) *details = r;
    if (r.status != AlignStatus::kOk) return initial;
    return r.T_target_source * initial;
}

namespace {

/// The parameters every learned method has. The variants with ICP refinement (`ogmm`,
/// `deepgmr`; kIcp) have the icp_* keys, the network-alone ones (`-noicp`) the checkpoint only.
/// A family's inference parameters (NetworkFamily::inference_params, e.g. OGMM's attention)
/// join them in MakeInfo.
template <bool kIcp>
struct LearnedOptions {
    /// Checkpoint directory; "" = the shipped one (ShippedCheckpointDir of the method's model).
    std::string checkpoint;
    double icp_max_correspondence_distance = 0.07;  ///< ICP refinement radius
    int icp_max_iterations = 30;                    ///< ICP iterations
    bool normalize = true;  ///< PairNormalization: pairs outside the training frame mapped in
    double data_unit = 1.0;  ///< data length of one training-frame unit [unit-sphere units]

    template <class F>
    void Fields(F&& f) {
        // MakeInfo appends the shipped folder of the method's model to this doc.
        f("checkpoint", checkpoint,
          "checkpoint directory from `regbench train`; \"\" = the shipped one, ");
        f("normalize", normalize,
          "map a pair outside the training frame (a point farther than 2 from the origin: "
          "millimetres, a scan in its camera frame) into the unit sphere (both clouds minus the "
          "source's centroid, over its radius) and the estimate back (docs/learned-methods.md); "
          "false: the data as given");
        f("data_unit", data_unit,
          "the data's length of one unit of the training frame [unit-sphere units]; `run` sets "
          "it from the pair file's scale (150 for `generate --scale 150`), so a scaled copy of a "
          "pair is divided by it and runs as the unit pair; used when normalize is true");
        if constexpr (kIcp) {
            f("icp_max_correspondence_distance", icp_max_correspondence_distance,
              "ICP refinement radius; 0.07 = 2 * overlap_radius of the OGMM code");
            f("icp_max_iterations", icp_max_iterations, "ICP iterations; 30 = Open3D default");
        }
    }
    void Validate(ParamCheck& c) const {
        c.Above("data_unit", data_unit, 0.0);
        if constexpr (kIcp) {
            c.Above("icp_max_correspondence_distance", icp_max_correspondence_distance, 0.0);
            c.AtLeast("icp_max_iterations", icp_max_iterations, 1);
        }
    }
};

/// The family's inference parameters of `params` (each a string, "" or one of its choices;
/// absent: ""), removed from `params`; the non-empty ones are the checkpoint's config overrides.
struct InferenceValues {
    nlohmann::json all = nlohmann::json::object();        ///< every key, as rows record them
    nlohmann::json overrides = nlohmann::json::object();  ///< the non-empty ones
};
InferenceValues TakeInferenceParams(const networks::NetworkFamily& family,
                                    const std::string& method, nlohmann::json& params) {
    InferenceValues out;
    for (const auto& p : family.inference_params) {
        std::string value;
        if (params.is_object() && params.contains(p.key)) {
            const nlohmann::json& given = params.at(p.key);
            Require(given.is_string(), method, p.key, "expects string, got " + given.dump());
            value = given.get<std::string>();
            params.erase(p.key);
        }
        std::string may = "\"\"";
        bool ok = value.empty();
        for (std::size_t i = 0; i < p.choices.size(); ++i) {
            may += (i + 1 == p.choices.size() ? " or \"" : ", \"") + p.choices[i] + "\"";
            ok = ok || value == p.choices[i];
        }
        Require(ok, method, p.key, "must be " + may + ", got \"" + value + "\"");
        out.all[p.key] = value;
        if (!value.empty()) out.overrides[p.key] = value;
    }
    return out;
}

std::string CheckpointLabel(const std::string& dir);

class LearnedMethod final : public RegistrationMethod {
public:
    template <bool kIcp>
    LearnedMethod(std::string name, std::string model_dir, const LearnedOptions<kIcp>& options,
                  const InferenceValues& inference)
        : name_(std::move(name)),
          icp_(kIcp),
          params_(ParamsToJson(options)),  // "" = shipped; the path used is in each row's extra
          options_{options.checkpoint, options.icp_max_correspondence_distance,
                   options.icp_max_iterations, options.normalize, options.data_unit},
          inference_(inference.overrides) {
        params_.update(inference.all);
        checkpoint_ =
            options_.checkpoint.empty() ? ShippedCheckpointDir(model_dir) : options_.checkpoint;
        checkpoint_label_ = CheckpointLabel(checkpoint_);
        try {
            const CheckpointInfo info = DescribeCheckpoint(checkpoint_);
            checkpoint_sha256_ = info.sha256;
            checkpoint_source_ = info.source;
        } catch (const std::exception&) {
            // an unreadable weights file fails each call when it loads, with its own message
        }
        // The GEMM rate of the floor, measured once per process, here in the process that
        // creates the method: the runner's isolated calls are forked from it and inherit it.
        (void)networks::ProcessGemmRate();
    }
    std::string Name() const override { return name_; }
    nlohmann::json Params() const override { return params_; }

protected:
    AlignResult DoAlign(const PointCloud& data_source, const PointCloud& data_target,
                        const AlignContext& context) override {
        AlignResult result;
        result.extra["checkpoint"] = checkpoint_;
        if (!checkpoint_label_.empty()) result.extra["checkpoint_label"] = checkpoint_label_;
        if (!checkpoint_sha256_.empty()) {
            result.extra["checkpoint_sha256"] = checkpoint_sha256_;
            result.extra["checkpoint_source"] = checkpoint_source_;
        }
        // The whole method (network and ICP) runs on the normalised pair; the estimate is
        // mapped back at the end.
        const PairNormalization frame =
            options_.normalize ? NormalizationOf(data_source, data_target, options_.data_unit)
                               : PairNormalization{};
        const PointCloud source = NormalizeCloud(data_source, frame);
        const PointCloud target = NormalizeCloud(data_target, frame);
        if (frame.applied) {
            result.extra["normalization"] = {
                {"centre", {frame.centre.x(), frame.centre.y(), frame.centre.z()}},
                {"scale", frame.scale}};
        }
        if (!Load(result)) return result;
        const auto t0 = std::chrono::steady_clock::now();
        const CpuStopwatch cpu(context.threads);
        // FPS starts etc. depend on the pair only (the seed), not on other runner threads.
        const networks::PairEstimate estimate =
            networks::EstimatePair(*net_, source, target, context.IntSeed(), context.threads);
        const Transform& T_net = estimate.T;
        result.extra["network_cpu_seconds"] = cpu.Elapsed();
        result.extra["network_seconds"] =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        // The network's multiply-accumulate floor on this machine (docs/performance.md,
        // section 6): its MACs for this config and these point counts over the single-thread
        // fp32 GEMM rate of this process.
        // A config the cost model cannot read (a key it needs missing) leaves them out.
        std::int64_t macs = 0;
        try {
            macs = networks::ComputeForwardCost(cost_config_, source.rows(), target.rows()).total;
        } catch (const std::exception&) {
            macs = 0;
        }
        if (macs > 0) {
            const networks::GemmRate& gemm = networks::ProcessGemmRate();
            result.extra["macs"] = macs;
            result.extra["gemm_gmac_per_s"] = gemm.macs_per_second * 1e-9;
            result.extra["floor_seconds"] = static_cast<double>(macs) / gemm.macs_per_second;
            result.extra["blas"] = networks::BlasDescription();
        }
        // Per-point outputs (overlap scores and the like) summarised by their mean.
        for (const auto& [key, mean] : estimate.source_point_means) {
            result.extra[key + "_mean"] = mean;
        }
        result.T_target_source = T_net;
        result.stop_reason = "network";
        if (icp_) {
            IcpRefineOptions o;
            o.max_correspondence_distance = options_.icp_max_correspondence_distance;
            o.max_iterations = options_.icp_max_iterations;
            AlignResult icp;
            result.T_target_source = IcpRefine(source, target, T_net, o, &icp);
            result.iterations = icp.iterations;
            result.stop_reason = "icp_" + icp.stop_reason;
            result.extra["icp"] = icp.extra;
        }
        result.T_target_source = DenormalizeTransform(result.T_target_source, frame);
        return result;
    }

private:
    /// Loads the checkpoint on first use; a failure fails this and every later pair with the
    /// same message instead of crashing the run.
    /// Runner threads share the method, so the first use is serialised.
    bool Load(AlignResult& result) {
        const std::lock_guard<std::mutex> lock(load_mutex_);
        if (!net_ && load_error_.empty()) {
            try {
                if (!std::filesystem::exists(checkpoint_)) {
                    throw std::runtime_error("checkpoint directory " + checkpoint_ +
                                             " does not exist (train one with `regbench train`, "
                                             "or set parameter checkpoint / $REGBENCH_MODELS)");
                }
                net_ = networks::LoadNetFromCheckpoint(checkpoint_, inference_);
                cost_config_ = networks::CheckpointNetConfig(checkpoint_, inference_);
            } catch (const std::exception& e) {
                load_error_ = name_ + ": " + e.what();
            }
        }
        if (net_) return true;
        result.status = AlignStatus::kFailed;
        result.message = load_error_;
        result.stop_reason = "no_checkpoint";
        return false;
    }

    /// The options of every learned method, resolved.
    struct Resolved {
        std::string checkpoint;
        double icp_max_correspondence_distance;
        int icp_max_iterations;
        bool normalize;
        double data_unit;
    };

    std::string name_;
    bool icp_;
    nlohmann::json params_;
    Resolved options_;
    std::string checkpoint_;
    std::string checkpoint_label_;  ///< "model M, step S" of checkpoint.json (report labels)
    std::string checkpoint_sha256_;  ///< of its weights file (DescribeCheckpoint)
    std::string checkpoint_source_;  ///< shipped | authors | trained
    nlohmann::json inference_;  ///< the inference parameters given (config overrides)
    nlohmann::json cost_config_;  ///< the network's zoo config, what ComputeForwardCost counts
    std::mutex load_mutex_;
    std::shared_ptr<networks::RegistrationNet> net_;
    std::string load_error_;
};

/// "model M, step S" (a `regbench train` checkpoint) or "model M, imported" (the authors'
/// weights, `import-checkpoint`) from a checkpoint.json.
std::string LabelOf(const nlohmann::json& j) {
    std::string model =
        j.contains("model") && j["model"].is_string() ? j["model"].get<std::string>() : "";
    if (model.empty() && j.contains("config") && j["config"].is_object() &&
        j["config"].contains("name") && j["config"]["name"].is_string()) {
        model = j["config"]["name"].get<std::string>();
    }
    std::string label = "model " + (model.empty() ? std::string("?") : model);
    if (j.contains("steps") && j["steps"].is_number_unsigned()) {
        label += ", step " + std::to_string(j["steps"].get<std::uint64_t>());
    } else if (j.contains("imported_from")) {
        label += ", imported";
        const auto& from = j["imported_from"];
        if (from.is_object() && from.contains("preset") && from["preset"].is_string() &&
            !from["preset"].get<std::string>().empty()) {
            label += " (preset " + from["preset"].get<std::string>() + ")";
        }
    }
    return label;
}

/// LabelOf dir/checkpoint.json; "" when it cannot be read.
std::string CheckpointLabel(const std::string& dir) {
    try {
        return LabelOf(networks::ReadCheckpointJson(dir));
    } catch (const std::exception&) {
        return "";  // a missing checkpoint fails each call with its own message
    }
}

/// Opens the checkpoint's checkpoint.json when the method is created, i.e. before a run
/// starts: a missing or unreadable checkpoint, a config its family refuses (sizes out of range),
/// or one of another network family (an OGMM checkpoint under `deepgmr` would run OGMM under
/// DeepGMR's name) is refused naming the folder. The weights load on first use.
void CheckCheckpoint(const networks::NetworkFamily& family, const networks::LearnedMethodSpec& method,
                     const std::string& dir, const nlohmann::json& inference) {
    if (!std::filesystem::is_directory(dir)) {
        throw std::invalid_argument(method.name + ": checkpoint directory " + dir +
                                    " does not exist (train one with `regbench train`, or set "
                                    "parameter checkpoint / $REGBENCH_MODELS)");
    }
    std::string arch;
    try {
        arch = networks::CheckCheckpointModel(dir, inference);
    } catch (const std::exception& e) {
        throw std::invalid_argument(method.name + ": " + e.what());
    }
    if (arch != family.arch) {
        std::string instead = arch;  // the method of the checkpoint's family with the same ICP
        for (const auto& m : networks::FindFamily(arch).methods) {
            if (m.icp == method.icp) instead = m.name;
        }
        throw std::invalid_argument(method.name + ": checkpoint " + dir + " holds a " + arch +
                                    " model (config.arch), not " + family.arch + "; run it as " +
                                    instead);
    }
}

template <bool kIcp>
MethodInfo MakeInfo(const networks::NetworkFamily& family,
                    const networks::LearnedMethodSpec& method) {
    using Options = LearnedOptions<kIcp>;
    MethodInfo info = DescribeParams<Options>(method.name, method.summary);
    info.paper_label = method.paper_label;
    info.cost = [cost = family.cost_class](const nlohmann::json&) { return cost; };
    const std::string model_dir = family.shipped_model;
    const std::string shipped = ShippedCheckpointDir(model_dir) + " ($REGBENCH_MODELS overrides)";
    info.param_docs.at("checkpoint") += shipped;
    info.schema["properties"]["checkpoint"]["description"] = info.param_docs.at("checkpoint");
    for (const auto& p : family.inference_params) {
        info.defaults[p.key] = "";
        info.param_docs[p.key] = p.doc;
        info.schema["properties"][p.key] = {{"type", "string"}, {"default", ""},
                                            {"description", p.doc}};
    }
    info.create = [family, method, known = info.defaults](
                      const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        const std::string& name = method.name;
        if (!kIcp && j.is_object() &&
            (j.contains("icp_max_correspondence_distance") || j.contains("icp_max_iterations"))) {
            throw std::invalid_argument(name +
                                        ": no ICP in this variant; drop the icp_* parameters");
        }
        if (j.is_object()) {  // unknown keys named with every known one, inference ones included
            for (const auto& item : j.items()) {
                if (known.contains(item.key())) continue;
                std::string list;
                for (const auto& k : known.items()) list += (list.empty() ? "" : ", ") + k.key();
                throw std::invalid_argument(name + ": unknown parameter '" + item.key() +
                                            "' (known: " + list + ")");
            }
        }
        nlohmann::json rest = j;
        const InferenceValues inference = TakeInferenceParams(family, name, rest);
        const auto o = ParseParams<Options>(name, rest);
        CheckCheckpoint(family, method,
                        o.checkpoint.empty() ? ShippedCheckpointDir(family.shipped_model)
                                             : o.checkpoint,
                        inference.overrides);
        return std::make_unique<LearnedMethod>(name, family.shipped_model, o, inference);
    };
    return info;
}

}  // namespace

CheckpointInfo DescribeCheckpoint(const std::string& dir) {
    namespace fs = std::filesystem;
    const nlohmann::json j = networks::ReadCheckpointJson(dir);  // throws naming the folder
    CheckpointInfo info;
    info.dir = dir;
    info.label = LabelOf(j);
    const std::string weights = j.contains("weights") && j["weights"].is_string()
                                    ? j["weights"].get<std::string>()
                                    : std::string("weights.pt");
    info.sha256 = Sha256File((fs::path(dir) / weights).string());
    std::error_code ec;
    const fs::path root = fs::weakly_canonical(ShippedCheckpointDir(""), ec);
    const fs::path here = fs::weakly_canonical(dir, ec);
    const auto rel = here.lexically_relative(root);
    const bool inside = !rel.empty() && rel.native().rfind("..", 0) != 0;
    info.source = j.contains("imported_from") ? "authors" : inside ? "shipped" : "trained";
    return info;
}

std::string DefaultCheckpointDir(const std::string& method) {
    for (const auto& family : networks::Families()) {
        for (const auto& m : family.methods) {
            if (m.name == method) return ShippedCheckpointDir(family.shipped_model);
        }
    }
    return "";
}

std::vector<MethodInfo> LearnedMethodInfos() {
    std::vector<MethodInfo> out;
    for (const auto& family : networks::Families()) {
        for (const auto& method : family.methods) {
            out.push_back(method.icp ? MakeInfo<true>(family, method)
                                     : MakeInfo<false>(family, method));
        }
    }
    return out;
}
}  // namespace regbench
