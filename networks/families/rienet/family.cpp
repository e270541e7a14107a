// The RIENet family (networks/family.hpp): RIENet (Shen et al., AAAI 2022), its zoo model, config
// checks, network, forward cost, method and the authors' state dict (supersyq/RIENet
// model.py, whose RIENET keys are regbench's names one to one: networks/families/rienet/net.hpp).
#include <stdexcept>
#include <utility>

#include "networks/checkpoint/authors_format.hpp"
#include "networks/cost.hpp"
#include "networks/families/rienet/net.hpp"
#include "networks/family.hpp"
#include "networks/family_config.hpp"
#include "networks/training/recipes.hpp"

namespace regbench::networks {
namespace {

/// The zoo model: the authors' ModelNet40 hyper-parameters (RienetConfig's defaults). The
/// authors trained with Adam 1e-3 for 100 epochs of ModelNet40; regbench trains it with the CPU
/// campaign recipe of ogmm-small so the learned rows compare like for like.
const std::vector<ZooModel<RienetConfig>>& Models() {
    static const std::vector<ZooModel<RienetConfig>> kModels = {
        {"rienet", [](RienetConfig&) {}, CampaignTrainingRecipe()}};
    return kModels;
}

/// The authors' RIENET: emb_dims from the DGCNN's last conv, dim from the discriminator's
/// first conv; the rest (k, k_nc, iterations, margins, keypoints) has no tensor and comes from
/// the import settings (the authors' per-dataset configs are the presets).
nlohmann::json InferConfig(const StateDict& sd, const std::string& file,
                           const nlohmann::json& settings) {
    nlohmann::json c = ZooModelConfig(Models(), "rienet", ToJson);
    for (const auto& [key, value] : settings.items()) c[key] = value;
    c["emb_dims"] =
        RequireAuthorsTensor(sd, "emb_nn.model.conv5.weight", 4, file, "a RIENet").size(0);
    c["dim"] =
        RequireAuthorsTensor(sd, "forwards.weight_function.model1.0.weight", 4, file, "a RIENet")
            .size(0);
    // "rienet" is the zoo model: the ModelNet40 config at the authors' widths.
    const nlohmann::json zoo = ZooModelConfig(Models(), "rienet", ToJson);
    bool zoo_config = c["emb_dims"] == 256 && c["dim"] == 8;
    for (const auto& [key, value] : settings.items()) zoo_config &= zoo.at(key) == value;
    if (!zoo_config) c["name"] = "rienet-authors";
    return c;
}

}  // namespace

NetworkFamily RienetFamily() {
    NetworkFamily f = NetFamily<RienetConfig, RienetNet>(
        "rienet",
        "RIENet (Shen et al., AAAI 2022): unsupervised, inlier evaluation of pseudo "
        "correspondences, weighted SVD",
        Models(), ToJson, RienetForwardMacs);
    f.cost_class = CostClass::kQuadratic;  // feature distances of all N x M pairs
    f.methods = {
        {"rienet", false, "RIENet network alone (LibTorch, CPU batch 1), no ICP", "RIENet"}};
    // Their config/*.yaml (supersyq/RIENet): list_k1 / list_k2 hold one value per iteration,
    // the same in every file, so one k and one k_nc here.
    f.authors = std::make_shared<AuthorsFormat>(AuthorsFormat{
        "RIENET (supersyq/RIENet model.py)",
        InferConfig,
        {{"k", 5, "DGCNN and inlier neighbourhood size (list_k1)"},
         {"k_nc", 5, "neighbourhood consensus size (list_k2)"},
         {"nn_margin", 0.7, "consensus margin (nn_margin)"},
         {"loss_margin", 0.01, "Huber threshold of the chamfer loss (loss_margin)"},
         {"keypoints", 256, "keypoints of the losses (n_keypoints)"},
         {"iterations", 3, "registration iterations (n_iters)"}},
        {{"modelnet40",
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
           {"iterations", 3}}}}});
    return f;
}

}  // namespace regbench::networks
