// The RIENet family (ogmm/family.hpp): RIENet (Shen et al., AAAI 2022), its zoo model, config
// checks, network, forward cost, method and the authors' state dict (supersyq/RIENet
// model.py, whose RIENET keys are regbench's names one to one: ogmm/rienet.hpp).
#include <stdexcept>
#include <utility>

#include "ogmm/authors_state_dict.hpp"
#include "ogmm/cost.hpp"
#include "ogmm/family.hpp"
#include "ogmm/ogmm_net.hpp"
#include "ogmm/rienet.hpp"

namespace regbench::ogmm {
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
/// first conv; the rest (k, k_nc, iterations, margins, keypoints) has no tensor and is the
/// authors' ModelNet40 config.
nlohmann::json InferConfig(const StateDict& sd, const std::string& file,
                           const ImportOptions& /*options*/) {
    nlohmann::json c = Named("rienet");
    c["emb_dims"] =
        RequireAuthorsTensor(sd, "emb_nn.model.conv5.weight", 4, file, "a RIENet").size(0);
    c["dim"] =
        RequireAuthorsTensor(sd, "forwards.weight_function.model1.0.weight", 4, file, "a RIENet")
            .size(0);
    if (c["emb_dims"] != 256 || c["dim"] != 8) c["name"] = "rienet-authors";
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
    f.methods = {{"rienet", false, "RIENet network alone (LibTorch, CPU batch 1), no ICP"}};
    auto authors = std::make_shared<AuthorsFormat>();
    authors->module = "RIENET (supersyq/RIENet model.py)";
    authors->infer_config = InferConfig;
    f.authors = std::move(authors);
    return f;
}

}  // namespace regbench::ogmm
