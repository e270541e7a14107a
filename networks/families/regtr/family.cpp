// The REGTR family (networks/family.hpp): the authors' REGTR (Yew and Lee, CVPR 2022) with their
// ModelNet config and a narrower CPU-trainable one, their config checks, network, forward cost,
// method and the authors' PyTorch state dict (yewzijian/RegTR src/models/regtr.py).
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include "networks/checkpoint/authors_format.hpp"
#include "networks/cost.hpp"
#include "networks/families/regtr/net.hpp"
#include "networks/family.hpp"
#include "networks/family_config.hpp"
#include "networks/training/recipes.hpp"

namespace regbench::networks {

namespace {

/// "regtr": the authors' ModelNet model (11.5 M parameters) and recipe (1e-4, weight decay
/// 1e-4, batch 4, halved every 100 of 400 epochs). "regtr-small": KPConv widths / 8,
/// d_embed 64, 4 heads, 2 layers, trained with the campaign's CPU recipe like the other small
/// learned models.
const std::vector<ZooModel<RegtrConfig>>& Models() {
    // Their step scheduler halves the LR every 127,800 steps (100 of the 400 epochs). Their
    // AdamW and gradient clipping (0.1) are not regbench options: Adam with weight decay and no
    // clipping here.
    static const std::vector<ZooModel<RegtrConfig>> kModels = {
        {"regtr",
         [](RegtrConfig&) {},
         {{"lr", 1e-4},
          {"weight_decay", 1e-4},
          {"batch", 4},
          {"epochs", 400},
          {"pairs_per_epoch", 4096},
          {"schedule", "multistep"},
          {"milestones", {0.25, 0.5, 0.75}},
          {"lr_gamma", 0.5}}},
        {"regtr-small",
         [](RegtrConfig& c) {
             c.first_feats_dim = 64;
             c.d_embed = 64;
             c.nhead = 4;
             c.d_feedforward = 128;
             c.num_encoder_layers = 2;
         },
         CampaignTrainingRecipe()}};
    return kModels;
}

/// The authors' REGTR: the KPConv width from the first block (first_feats_dim / 2 outputs), the
/// embedding from feat_proj, the layers from those present; the heads cannot be read from the
/// file (nn.MultiheadAttention stores none): the import setting nhead (their 8).
nlohmann::json InferConfig(const StateDict& sd, const std::string& file,
                           const nlohmann::json& settings) {
    const torch::Tensor& first =
        RequireAuthorsTensor(sd, "kpf_encoder.encoder_blocks.0.KPConv.weights", 3, file, "a REGTR");
    const torch::Tensor& proj = RequireAuthorsTensor(sd, "feat_proj.weight", 2, file, "a REGTR");
    const torch::Tensor& ff =
        RequireAuthorsTensor(sd, "transformer_encoder.layers.0.linear1.weight", 2, file, "a REGTR");
    if (first.size(0) != 15 || first.size(1) != 1) {
        RefuseAuthorsFile(file,
                          "tensor kpf_encoder.encoder_blocks.0.KPConv.weights is not a "
                          "15-point KPConv of the 1-wide input feature");
    }
    std::set<std::string> layers;
    const std::string prefix = "transformer_encoder.layers.";
    for (const auto& [key, tensor] : sd) {
        (void)tensor;
        if (key.rfind(prefix, 0) == 0) {
            layers.insert(key.substr(prefix.size(), key.find('.', prefix.size()) - prefix.size()));
        }
    }
    nlohmann::json c = ZooModelConfig(Models(), "regtr", ToJson);
    c["first_feats_dim"] = 2 * first.size(2);
    c["d_embed"] = proj.size(0);
    c["d_feedforward"] = ff.size(0);
    c["num_encoder_layers"] = static_cast<int>(layers.size());
    const int64_t heads = settings.at("nhead").get<int64_t>();
    if (heads < 1 || proj.size(0) % heads != 0) {
        RefuseAuthorsFile(file, "setting nhead = " + std::to_string(heads) +
                                    " does not divide d_embed " + std::to_string(proj.size(0)) +
                                    " (tensor feat_proj.weight): give --setting nhead=H");
    }
    c["nhead"] = heads;
    return c;
}

}  // namespace

NetworkFamily RegtrFamily() {
    NetworkFamily f = NetFamily<RegtrConfig, RegtrNet>(
        "regtr",
        "REGTR (Yew and Lee, CVPR 2022): KPConv superpoints, cross-attention transformer, "
        "regressed correspondences and weighted Kabsch",
        Models(), ToJson, RegtrForwardMacs);
    // Attention over all superpoints of both clouds: O(N M).
    f.cost_class = CostClass::kQuadratic;
    f.methods = {{"regtr", false,
                  "REGTR network alone (LibTorch, CPU batch 1): regressed correspondences, "
                  "weighted Kabsch",
                  "REGTR"}};
    f.authors = std::make_shared<AuthorsFormat>(
        AuthorsFormat{"RegTR (yewzijian/RegTR src/models/regtr.py)",
                      InferConfig,
                      {{"nhead", 8, "attention heads (their nhead; no tensor stores it)"}}});
    return f;
}

}  // namespace regbench::networks
