// The DeepGMR family (networks/family.hpp): the original DeepGMR (Yuan et al., ECCV 2020) and the
// OGMM paper's variant, their zoo models, config checks, network, forward cost, methods and the
// authors' state dict (wentaoyuan/deepgmr model.py).
#include <stdexcept>
#include <utility>

#include "networks/checkpoint/authors_format.hpp"
#include "networks/cost.hpp"
#include "networks/families/deepgmr/net.hpp"
#include "networks/families/deepgmr/rri.hpp"
#include "networks/family.hpp"
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

nlohmann::json Named(const std::string& name) {
    DeepGmrConfig c;
    c.name = name;
    nlohmann::json train = OriginalRecipe();
    if (name == "deepgmr-orig") {
        c.features = DeepGmrFeatures::kRri;
    } else if (name == "deepgmr-orig-xyz") {
        c.features = DeepGmrFeatures::kXyz;
    } else if (name == "deepgmr" || name == "deepgmr-small") {
        c.features = DeepGmrFeatures::kDgcnn;
        c.loss = DeepGmrLoss::kPose;
        c.clusters = 128;
        c.emb_dims = 512;
        c.head_hidden = 256;
        train = OgmmTrainingRecipe();  // the OGMM authors trained their DeepGMR baseline so
        if (name == "deepgmr-small") {
            // Width of ogmm-small, the shipped (CPU-trained) OGMM: d = 128, J = 32; a CPU budget
            // of minutes needs lr 1e-3 to move at all, and small batches to take many steps.
            c.clusters = 32;
            c.emb_dims = 128;
            c.head_hidden = 128;
            train = CampaignTrainingRecipe();
        }
    } else {
        throw std::invalid_argument("deepgmr: unknown model '" + name + "'");
    }
    nlohmann::json j = ToJson(c);
    j["train"] = train;
    return j;
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
        c = Named("deepgmr-orig-xyz");
    } else if (d_in >= 8 && d_in % 4 == 0) {
        c = Named("deepgmr-orig");
        c["rri_k"] = d_in / 4;
        c["rri_variant"] = ToString(ParseRriVariant(settings.at("rri_variant").get<std::string>()));
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
    NetworkFamily f;
    f.arch = "deepgmr";
    f.summary = "DeepGMR (Yuan et al., ECCV 2020): learned GMM correspondences, closed-form pose";
    f.models = {"deepgmr", "deepgmr-small", "deepgmr-orig", "deepgmr-orig-xyz"};
    f.shipped_model = "deepgmr";
    f.named_config = Named;
    f.config_docs = {
        {"features",
         "\"rri\" (original: PointNet on RRI features), \"xyz\" (original on "
         "centred xyz) or \"dgcnn\" (the OGMM paper's variant: DGCNN, CONV3 head)"},
        {"clusters", "GMM components J"},
        {"rri_k", "RRI neighbours (features rri)"},
        {"d_model",
         "PointNet feature width (rri, xyz; the original's --d_model; written only "
         "when not 1024)"},
        {"rri_variant", "RRI phi orientation: \"cuda\" (released models) or \"numpy\""},
        {"emb_dims", "DGCNN feature width (features dgcnn)"},
        {"dgcnn_k", "DGCNN neighbours, the point itself included (features dgcnn)"},
        {"head_hidden", "CONV3 head hidden width (features dgcnn)"},
        {"loss",
         "\"transform\" (original: T12 and T21 against T_gt) or \"pose\" (DCP style: "
         "rotation and translation)"}};
    f.check_config = [](const nlohmann::json& c) { DeepGmrConfigFromJson(c); };
    f.build = [](const nlohmann::json& c) -> std::shared_ptr<RegistrationNet> {
        return std::make_shared<DeepGmrNet>(DeepGmrConfigFromJson(c));
    };
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
