// The RGM family (networks/family.hpp): the authors' RGM (Fu et al., CVPR 2021) and a narrower
// CPU-trainable one, their config checks, network, forward cost, method and the authors'
// PyTorch state dict (fukexue/RGM models/Net.py; their repository has no licence, so regbench
// reads its layout and ships none of its code or weights).
#include <stdexcept>
#include <string>
#include <utility>

#include "networks/checkpoint/authors_format.hpp"
#include "networks/cost.hpp"
#include "networks/families/rgm/net.hpp"
#include "networks/family.hpp"
#include "networks/family_config.hpp"
#include "networks/training/recipes.hpp"

namespace regbench::networks {

namespace {

/// "rgm": the authors' widths; their recipe is SGD (lr 1e-3, Nesterov momentum 0.9, x0.2 at
/// epochs 120 and 140 of 200, batch 4): regbench trains with Adam only, so the recipe keeps
/// their lr, batch, length and drops. "rgm-small": every width / 8 (about 0.4 M parameters),
/// trained with the campaign's CPU recipe like the other learned rows.
const std::vector<ZooModel<RgmConfig>>& Models() {
    static const std::vector<ZooModel<RgmConfig>> kModels = {
        {"rgm",
         [](RgmConfig&) {},
         {{"lr", 1e-3},
          {"weight_decay", 0.0},
          {"batch", 4},
          {"epochs", 200},
          {"pairs_per_epoch", 9843},
          {"schedule", "multistep"},
          {"milestones", {120.0 / 200, 140.0 / 200}},
          {"lr_gamma", 0.2}}},
        {"rgm-small", [](RgmConfig& c) { c.width_divisor = 8; }, CampaignTrainingRecipe()}};
    return kModels;
}

/// The authors' RGM: the width from the first DGCNN convolution (64 / divisor outputs, 6
/// inputs: their xyz + gxyz features); the rest of the layout is checked by the strict load.
nlohmann::json InferConfig(const StateDict& sd, const std::string& file,
                           const nlohmann::json& /*settings*/) {
    const torch::Tensor& first =
        RequireAuthorsTensor(sd, "pointfeaturer.conv1.weight", 4, file, "an RGM");
    const int64_t w = first.size(0);
    if (w < 1 || 64 % w != 0 || first.size(1) != 6) {
        RefuseAuthorsFile(file, "tensor pointfeaturer.conv1.weight has shape [" +
                                    std::to_string(w) + ", " + std::to_string(first.size(1)) +
                                    ", 1, 1]: not RGM's DGCNN on xyz + gxyz (64 / d outputs, 6 "
                                    "inputs)");
    }
    RequireAuthorsTensor(sd, "gmattend0.model.encoder.layers.0.self_attn.linears.0.weight", 2,
                         file, "an RGM (transformer attention)");
    nlohmann::json c = ZooModelConfig(Models(), "rgm", ToJson);
    c["width_divisor"] = 64 / w;
    return c;
}

}  // namespace

NetworkFamily RgmFamily() {
    NetworkFamily f = NetFamily<RgmConfig, RgmNet>(
        "rgm",
        "RGM (Fu et al., CVPR 2021): deep graph matching (DGCNN, transformer soft graphs, "
        "Sinkhorn), linear assignment and SVD, two rounds both ways",
        Models(), ToJson, RgmForwardMacs);
    // Transformer attention, soft adjacencies and the N x M correspondence: quadratic.
    f.cost_class = CostClass::kQuadratic;
    f.methods = {{"rgm", false,
                  "RGM network and its test-time assignment + SVD (LibTorch, CPU batch 1), as "
                  "the paper ran it",
                  "RGM"}};
    f.authors = std::make_shared<AuthorsFormat>(
        AuthorsFormat{"RGM (fukexue/RGM models/Net.py)", InferConfig});
    return f;
}

}  // namespace regbench::networks
