// The OMNet family (networks/family.hpp): the authors' OMNet (Xu et al., ICCV 2021) and a narrower
// CPU-trainable one, their config checks, network, forward cost, method and the authors'
// PyTorch state dict (hxwork/OMNet_Pytorch model/net.py).
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include "networks/checkpoint/authors_format.hpp"
#include "networks/cost.hpp"
#include "networks/family.hpp"
#include "networks/families/omnet/net.hpp"
#include "networks/training/recipes.hpp"

namespace regbench::networks {

namespace {

/// "omnet": the authors' widths and recipe (Adam 1e-4, constant LR: their ExponentialLR has
/// gamma 1; batch 64). "omnet-small": every width / 4 (3.4 M parameters), trained with
/// ogmm-small's CPU recipe (lr 1e-3, batch 8, 512 pairs an epoch, 40 epochs, multistep) so
/// the learned rows of the tables come from one recipe.
nlohmann::json Named(const std::string& name) {
    OmnetConfig c;
    c.name = name;
    nlohmann::json train;
    if (name == "omnet") {
        train = {{"lr", 1e-4},    {"weight_decay", 0.0},     {"batch", 64},
                 {"epochs", 100}, {"pairs_per_epoch", 4096}, {"schedule", "constant"}};
    } else if (name == "omnet-small") {
        c.width_divisor = 4;
        train = CampaignTrainingRecipe();
    } else {
        throw std::invalid_argument("omnet: unknown model '" + name + "'");
    }
    nlohmann::json j = ToJson(c);
    j["train"] = train;
    return j;
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
    nlohmann::json c = Named("omnet");
    c["width_divisor"] = 64 / w;
    c["iterations"] = static_cast<int>(encoders.size());
    return c;
}

ForwardCost Cost(const nlohmann::json& c, std::int64_t n, std::int64_t m) {
    return CostOfParts(OmnetForwardMacs(c, n, m));
}

}  // namespace

NetworkFamily OmnetFamily() {
    NetworkFamily f;
    f.arch = "omnet";
    f.summary =
        "OMNet (Xu et al., ICCV 2021): learned overlap masks, iterative global-feature pose "
        "regression";
    f.models = {"omnet", "omnet-small"};
    f.shipped_model = "omnet";
    f.named_config = Named;
    f.config_docs = {
        {"iterations", "refinement iterations, each with its own weights (the authors' titer)"},
        {"width_divisor",
         "every hidden width / this (1: the authors' 53.7 M parameters; 4: 3.4 M); divides 64"},
        {"mask_delay", "first iterations that use no overlap mask (the authors': 2)"},
        {"overlap_dist",
         "training labels: a point overlaps when nearer than this to the other cloud under "
         "the true motion [unit-sphere units]"},
        {"quat_weight", "weight of the L1 quaternion loss (the authors' loss_alpha1)"},
        {"trans_weight", "weight of the squared translation loss (the authors' loss_alpha2)"}};
    f.check_config = [](const nlohmann::json& c) { OmnetConfigFromJson(c); };
    f.build = [](const nlohmann::json& c) -> std::shared_ptr<RegistrationNet> {
        return std::make_shared<OmnetNet>(OmnetConfigFromJson(c));
    };
    f.forward_cost = Cost;
    // Per-point convolutions and max-pooling: linear in N + M (no kNN, no N x M term).
    f.cost_class = CostClass::kNearLinear;
    f.methods = {
        {"omnet", false, "OMNet network alone (LibTorch, CPU batch 1), as the paper ran it",
         "OMNET"}};
    auto authors = std::make_shared<AuthorsFormat>();
    authors->module = "OMNet (hxwork/OMNet_Pytorch model/net.py)";
    authors->infer_config = InferConfig;
    f.authors = std::move(authors);
    return f;
}

}  // namespace regbench::networks
