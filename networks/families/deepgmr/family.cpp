// The DeepGMR family (networks/family.hpp): the original DeepGMR (Yuan et al., ECCV 2020) and the
// OGMM paper's variant, their zoo models, config checks, network, forward cost, methods and the
// authors' state dict (wentaoyuan/deepgmr model.py).
#include <stdexcept>
#include <utility>

#include "networks/checkpoint/authors_format.hpp"
#include "networks/cost.hpp"
#include "networks/families/deepgmr/net.hpp"
#include "networks/family.hpp"
#include "networks/family_config.hpp"
#include "networks/training/recipes.hpp"

namespace regbench::networks {
namespace {

using Int = std::int64_t;

/// Training recipe of the original DeepGMR (Adam 1e-3, plateau halving, batch 32, 100 epochs).
nlohmann::json OriginalRecipe() {
    return {{"lr", 1e-3},      {"weight_decay", 0.0},     {"batch", 32},
            {"epochs", 100},   {"pairs_per_epoch", 4096}, {"schedule", "plateau"},
            {"lr_gamma", 0.5}, {"plateau_patience", 10},  {"min_lr", 1e-6}};
}

/// The OGMM paper's variant: OGMM's DGCNN features and the pose loss, at a width of `d`,
/// `clusters` components and a head of `hidden`.
void PaperVariant(DeepGmrConfig& c, int d, int clusters, int hidden) {
    c.features = DeepGmrFeatures::kDgcnn;
    c.loss = DeepGmrLoss::kPose;
    c.emb_dims = d;
    c.clusters = clusters;
    c.head_hidden = hidden;
}

/// "deepgmr": the OGMM paper's variant as the OGMM authors trained their DeepGMR baseline.
/// "deepgmr-small": the width of ogmm-small, the shipped (CPU-trained) OGMM: d = 128, J = 32; a
/// CPU budget of minutes needs lr 1e-3 to move at all, and small batches to take many steps.
/// "deepgmr-orig" / "-xyz": the original on RRI / centred-xyz features and its recipe.
const std::vector<ZooModel<DeepGmrConfig>>& Models() {
    static const std::vector<ZooModel<DeepGmrConfig>> kModels = {
        {"deepgmr", [](DeepGmrConfig& c) { PaperVariant(c, 512, 128, 256); },
         OgmmTrainingRecipe()},
        {"deepgmr-small", [](DeepGmrConfig& c) { PaperVariant(c, 128, 32, 128); },
         CampaignTrainingRecipe()},
        {"deepgmr-orig", [](DeepGmrConfig& c) { c.features = DeepGmrFeatures::kRri; },
         OriginalRecipe()},
        {"deepgmr-orig-xyz", [](DeepGmrConfig& c) { c.features = DeepGmrFeatures::kXyz; },
         OriginalRecipe()}};
    return kModels;
}

/// The original's DeepGMR(args): xyz or RRI input from the first conv's channels, d_model and J
/// from their layers. Its T-Net (--use_tnet) is not part of regbench's deepgmr-orig.
nlohmann::json InferConfig(const StateDict& sd, const std::string& file,
                           const nlohmann::json& settings) {
    for (const auto& [k, v] : sd) {
        (void)v;
        if (k.rfind("backbone.tnet.", 0) == 0) {
            RefuseAuthorsFile(file, "tensor " + k +
                                        " belongs to DeepGMR's T-Net (--use_tnet), which "
                                        "regbench's deepgmr-orig does not have");
        }
    }
    const torch::Tensor& first =
        RequireAuthorsTensor(sd, "backbone.encoder.0.0.weight", 3, file, "a DeepGMR");
    const int64_t d_in = first.size(1);
    nlohmann::json c;
    if (d_in == 3) {
        c = ZooModelConfig(Models(), "deepgmr-orig-xyz", ToJson);
    } else if (d_in >= 8 && d_in % 4 == 0) {
        c = ZooModelConfig(Models(), "deepgmr-orig", ToJson);
        c["rri_k"] = d_in / 4;
        c["rri_variant"] = settings.at("rri_variant");  // checked with the whole config
    } else {
        RefuseAuthorsFile(file, "tensor backbone.encoder.0.0.weight has " + std::to_string(d_in) +
                                    " input channels: neither xyz (3) nor RRI (4k)");
    }
    c["d_model"] =
        RequireAuthorsTensor(sd, "backbone.encoder.3.0.weight", 3, file, "DeepGMR").size(0);
    c["clusters"] =
        RequireAuthorsTensor(sd, "backbone.decoder.3.weight", 3, file, "DeepGMR").size(0);
    return c;
}

void CheckExport(const nlohmann::json& config, const std::string& where) {
    if (config.value("features", "") == "dgcnn") {
        RefuseAuthorsFile(where,
                          "holds the OGMM paper's DeepGMR variant (DGCNN features), which the "
                          "DeepGMR authors' module cannot hold; only deepgmr-orig / -xyz export");
    }
}

ForwardCost Cost(const nlohmann::json& c, Int n, Int m) {
    const std::string features = c.at("features").get<std::string>();
    const Int j = CostKey(c, "clusters");
    ForwardCost cost;
    for (const Int own : {n, m}) {
        if (features == "dgcnn") {
            const Int d = CostKey(c, "emb_dims"), h = CostKey(c, "head_hidden");
            AddMacs(cost, "dgcnn", DgcnnMacs(own, CostKey(c, "dgcnn_k"), d));
            AddMacs(cost, "head", own * (d * h + h * h + h * j));
        } else {
            const Int d_in = features == "rri" ? 4 * CostKey(c, "rri_k") : 3;
            AddMacs(cost, "pointnet_encoder",
                    own * (d_in * 64 + 64 * 128 + 128 * 256 + 256 * 1024));
            AddMacs(cost, "pointnet_decoder", own * (2048 * 512 + 512 * 256 + 256 * 128 + 128 * j));
        }
        // Mixture: weighted means (3 n J), squared distances (3 n J), variances (n J).
        AddMacs(cost, "mixture", 7 * own * j);
    }
    AddMacs(cost, "register", 2 * 9 * j);  // two weighted 3x3 covariances (T and T21)
    return cost;
}

}  // namespace

NetworkFamily DeepGmrFamily() {
    NetworkFamily f = NetFamily<DeepGmrConfig, DeepGmrNet>(
        "deepgmr",
        "DeepGMR (Yuan et al., ECCV 2020): learned GMM correspondences, closed-form pose",
        Models(), ToJson);
    f.forward_cost = Cost;
    f.methods = {
        {"deepgmr", true, "DeepGMR, OGMM paper's variant (DGCNN encoder) + Open3D ICP refinement",
         "DeepGMR"},
        {"deepgmr-noicp", false, "DeepGMR, OGMM paper's variant (DGCNN encoder), network alone"}};
    auto authors = std::make_shared<AuthorsFormat>();
    authors->module = "DeepGMR (wentaoyuan/deepgmr model.py)";
    authors->infer_config = InferConfig;
    authors->check_export = CheckExport;
    // The released checkpoints (modelnet_clean, modelnet_noisy, modelnet_unseen, icl_nuim) were
    // all trained with the GPU RRI kernel; the weights fix everything else.
    authors->settings = {{"rri_variant", "cuda",
                          "RRI orientation at run time: \"cuda\" (the GPU kernel the released "
                          "models were trained with) or \"numpy\" (the CPU fallback of the "
                          "authors' test.py)"}};
    f.authors = std::move(authors);
    return f;
}

}  // namespace regbench::networks
