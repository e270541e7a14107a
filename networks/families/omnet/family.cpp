// The OMNet family (networks/family.hpp): the authors' OMNet (Xu et al., ICCV 2021) and a narrower
// CPU-trainable one, their config checks, network, forward cost, method and the authors'
// PyTorch state dict (hxwork/OMNet_Pytorch model/net.py).
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include "networks/checkpoint/authors_format.hpp"
#include "networks/cost.hpp"
#include "networks/families/omnet/net.hpp"
#include "networks/family.hpp"
#include "networks/family_config.hpp"
#include "networks/training/recipes.hpp"

namespace regbench::networks {

namespace {

/// "omnet": the authors' widths and recipe (Adam 1e-4, constant LR: their ExponentialLR has
/// gamma 1; batch 64). "omnet-small": every width / 4 (3.4 M parameters), trained with
/// ogmm-small's CPU recipe (lr 1e-3, batch 8, 512 pairs an epoch, 40 epochs, multistep) so
/// the learned rows of the tables come from one recipe.
const std::vector<ZooModel<OmnetConfig>>& Models() {
    static const std::vector<ZooModel<OmnetConfig>> kModels = {
        {"omnet",
         [](OmnetConfig&) {},
         {{"lr", 1e-4},
          {"weight_decay", 0.0},
          {"batch", 64},
          {"epochs", 100},
          {"pairs_per_epoch", 4096},
          {"schedule", "constant"}}},
        {"omnet-small", [](OmnetConfig& c) { c.width_divisor = 4; }, CampaignTrainingRecipe()}};
    return kModels;
}

/// The authors' OMNet: the width from the first encoder convolution (64 / divisor output
/// channels), the iterations from the encoders present.
nlohmann::json InferConfig(const StateDict& sd, const std::string& file,
                           const nlohmann::json& /*settings*/) {
    const torch::Tensor& first =
        RequireAuthorsTensor(sd, "encoder.0.conv_block1.0.weight", 3, file, "an OMNet");
    const int64_t w = first.size(0);
    if (w < 1 || 64 % w != 0 || first.size(1) != 3) {
        RefuseAuthorsFile(file, "tensor encoder.0.conv_block1.0.weight has shape [" +
                                    std::to_string(w) + ", " + std::to_string(first.size(1)) +
                                    ", 1]: not an OMNet encoder (64 / d outputs, 3 inputs)");
    }
    std::set<std::string> encoders;
    for (const auto& [key, tensor] : sd) {
        (void)tensor;
        if (key.rfind("encoder.", 0) == 0) encoders.insert(key.substr(8, key.find('.', 8) - 8));
    }
    nlohmann::json c = ZooModelConfig(Models(), "omnet", ToJson);
    c["width_divisor"] = 64 / w;
    c["iterations"] = static_cast<int>(encoders.size());
    return c;
}

}  // namespace

NetworkFamily OmnetFamily() {
    NetworkFamily f = NetFamily<OmnetConfig, OmnetNet>(
        "omnet",
        "OMNet (Xu et al., ICCV 2021): learned overlap masks, iterative global-feature pose "
        "regression",
        Models(), ToJson, OmnetForwardMacs);
    // Per-point convolutions and max-pooling: linear in N + M (no kNN, no N x M term).
    f.cost_class = CostClass::kNearLinear;
    f.methods = {
        {"omnet", false, "OMNet network alone (LibTorch, CPU batch 1), as the paper ran it",
         "OMNET"}};
    f.authors = std::make_shared<AuthorsFormat>(
        AuthorsFormat{"OMNet (hxwork/OMNet_Pytorch model/net.py)", InferConfig});
    return f;
}

}  // namespace regbench::networks
