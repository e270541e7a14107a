// The RIENet family (networks/family.hpp): RIENet (Shen et al., AAAI 2022), its zoo model, config
// checks, network, forward cost, method and the authors' state dict (supersyq/RIENet
// model.py, whose RIENET keys are regbench's names one to one: networks/families/rienet/net.hpp).
#include <stdexcept>
#include <utility>

#include "networks/checkpoint/authors_format.hpp"
#include "networks/cost.hpp"
#include "networks/family.hpp"
#include "networks/families/rienet/net.hpp"
#include "networks/training/recipes.hpp"

namespace regbench::networks {
namespace {

/// The zoo config: the authors' ModelNet40 hyper-parameters (RienetConfig's defaults).
nlohmann::json Named(const std::string& name) {
    if (name != "rienet") throw std::invalid_argument("rienet: unknown model '" + name + "'");
    RienetConfig c;
    c.name = name;
    nlohmann::json j = ToJson(c);
    // The authors trained with Adam 1e-3 for 100 epochs of ModelNet40; regbench trains it
    // with the CPU campaign recipe of ogmm-small so the learned rows compare like for like.
    j["train"] = CampaignTrainingRecipe();
    return j;
}

/// The authors' RIENET: emb_dims from the DGCNN's last conv, dim from the discriminator's
/// first conv; the rest (k, k_nc, iterations, margins, keypoints) has no tensor and comes from
/// the import settings (the authors' per-dataset configs are the presets).
nlohmann::json InferConfig(const StateDict& sd, const std::string& file,
                           const nlohmann::json& settings) {
    nlohmann::json c = Named("rienet");
    for (const auto& [key, value] : settings.items()) c[key] = value;
    c["emb_dims"] =
        RequireAuthorsTensor(sd, "emb_nn.model.conv5.weight", 4, file, "a RIENet").size(0);
    c["dim"] =
        RequireAuthorsTensor(sd, "forwards.weight_function.model1.0.weight", 4, file, "a RIENet")
            .size(0);
    // "rienet" is the zoo model: the ModelNet40 config at the authors' widths.
    const nlohmann::json zoo = Named("rienet");
    bool zoo_config = c["emb_dims"] == 256 && c["dim"] == 8;
    for (const auto& [key, value] : settings.items()) zoo_config &= zoo.at(key) == value;
    if (!zoo_config) c["name"] = "rienet-authors";
    return c;
}

ForwardCost Cost(const nlohmann::json& c, std::int64_t n, std::int64_t m) {
    return CostOfParts(RienetForwardMacs(c, n, m));
}

}  // namespace

NetworkFamily RienetFamily() {
    NetworkFamily f;
    f.arch = "rienet";
    f.summary =
        "RIENet (Shen et al., AAAI 2022): unsupervised, inlier evaluation of pseudo "
        "correspondences, weighted SVD";
    f.models = {"rienet"};
    f.shipped_model = "rienet";
    f.named_config = Named;
    f.config_docs = {
        {"emb_dims", "light DGCNN feature width (the authors' emb_dims)"},
        {"dim", "inlier discriminator width (the authors' dim: 8 ModelNet40, 16 ICL-NUIM)"},
        {"iterations", "registration iterations with shared weights (n_iters)"},
        {"k", "DGCNN and inlier neighbourhood size, the point itself included (list_k1)"},
        {"k_nc", "neighbourhood consensus size, the point itself included (list_k2)"},
        {"nn_margin", "consensus margin: feature distances scaled by exp(margin - consensus)"},
        {"loss_margin", "Huber threshold of the chamfer loss, in cloud units (loss_margin)"},
        {"keypoints", "points with the highest inlier weight in the losses (at most N)"}};
    f.check_config = [](const nlohmann::json& c) { RienetConfigFromJson(c); };
    f.build = [](const nlohmann::json& c) -> std::shared_ptr<RegistrationNet> {
        return std::make_shared<RienetNet>(RienetConfigFromJson(c));
    };
    f.forward_cost = Cost;
    f.cost_class = CostClass::kQuadratic;  // feature distances of all N x M pairs
    f.methods = {
        {"rienet", false, "RIENet network alone (LibTorch, CPU batch 1), no ICP", "RIENet"}};
    auto authors = std::make_shared<AuthorsFormat>();
    authors->module = "RIENET (supersyq/RIENet model.py)";
    authors->infer_config = InferConfig;
    // Their config/*.yaml (supersyq/RIENet): list_k1 / list_k2 hold one value per iteration,
    // the same in every file, so one k and one k_nc here.
    authors->settings = {{"k", 5, "DGCNN and inlier neighbourhood size (list_k1)"},
                         {"k_nc", 5, "neighbourhood consensus size (list_k2)"},
                         {"nn_margin", 0.7, "consensus margin (nn_margin)"},
                         {"loss_margin", 0.01, "Huber threshold of the chamfer loss (loss_margin)"},
                         {"keypoints", 256, "keypoints of the losses (n_keypoints)"},
                         {"iterations", 3, "registration iterations (n_iters)"}};
    authors->presets = {{"modelnet40",
                         "config/train.yaml: ModelNet40, same and unseen categories (the defaults)",
                         {{"k", 5},
                          {"k_nc", 5},
                          {"nn_margin", 0.7},
                          {"loss_margin", 0.01},
                          {"keypoints", 256},
                          {"iterations", 3}}},
                        {"7scenes",
                         "config/train7.yaml: 7Scenes",
                         {{"k", 8},
                          {"k_nc", 8},
                          {"nn_margin", 0.5},
                          {"loss_margin", 0.01},
                          {"keypoints", 768},
                          {"iterations", 3}}},
                        {"icl_nuim",
                         "config/train-icl.yaml: ICL-NUIM",
                         {{"k", 32},
                          {"k_nc", 10},
                          {"nn_margin", 0.5},
                          {"loss_margin", 0.01},
                          {"keypoints", 768},
                          {"iterations", 3}}},
                        {"kitti",
                         "config/train-k.yaml: KITTI",
                         {{"k", 32},
                          {"k_nc", 8},
                          {"nn_margin", 0.5},
                          {"loss_margin", 0.0009},
                          {"keypoints", 1024},
                          {"iterations", 3}}}};
    f.authors = std::move(authors);
    return f;
}

}  // namespace regbench::networks
