// The OGMM family (networks/family.hpp): its zoo models, config checks, network, forward cost,
// methods and the authors' GMMReg state dict (gfmei/ogmm models/gmmreg.py).
#include <algorithm>
#include <stdexcept>
#include <utility>
#include <vector>

#include "networks/checkpoint/authors_format.hpp"
#include "networks/cost.hpp"
#include "networks/families/ogmm/net.hpp"
#include "networks/family.hpp"
#include "networks/family_config.hpp"
#include "networks/training/recipes.hpp"

namespace regbench::networks {

namespace {

using Int = std::int64_t;

/// OGMM's own config plus "arch"/"name" and the authors' recipe (lr raised to 1e-3 and batch 8
/// for the reduced CPU configs, as for deepgmr-small).
nlohmann::json Named(const std::string& name) {
    nlohmann::json j = OgmmConfigToJson(ParseOgmmConfig(OgmmNamedConfig(name)));
    j["arch"] = "ogmm";
    j["name"] = name;
    j["train"] = name == "ogmm" ? OgmmTrainingRecipe() : CampaignTrainingRecipe();
    return j;
}

/// Attention block, n queries onto a keys of width d: Q and merge (2 d^2 per query), the update
/// MLP 2d->2d->d (6 d^2 per query), K and V (2 d^2 per key), scores and messages (2 n a d).
Int Attention(Int n, Int a, Int d) { return 8 * d * d * n + 2 * d * d * a + 2 * n * a * d; }

/// Overlap head per point: proj Conv2(d -> d/2 -> 1), CONV3_b (d+2 -> 2d -> 2d -> d),
/// CONV3_o (d -> d/2 -> d/2 -> 1).
Int OverlapHeadPerPoint(Int d) {
    const Int h = d / 2;
    return (d * h + h) + ((d + 2) * 2 * d + 4 * d * d + 2 * d * d) + (d * h + h * h + h);
}

ForwardCost OgmmCost(const nlohmann::json& c, Int n, Int m) {
    const Int d = CostKey(c, "emb_dims"), k = CostKey(c, "k"), spe_k = CostKey(c, "spe_k");
    const Int anchors = CostKey(c, "anchors"), clusters = CostKey(c, "clusters");
    const Int rounds = CostKey(c, "gmm_iterations");
    const bool spe = c.at("spe").get<bool>(), csa = c.at("csa").get<bool>();
    const bool osp = c.at("osp").get<bool>();
    const bool full = c.at("attention").get<std::string>() == "full";
    const auto keys = [&](Int points) { return full ? points : std::min(anchors, points); };
    ForwardCost cost;
    for (const auto& [own, other] : {std::pair<Int, Int>{n, m}, std::pair<Int, Int>{m, n}}) {
        AddMacs(cost, "dgcnn", DgcnnMacs(own, k, d));
        // SPE: distance branch 1->64->d/2, angle branch 1->64 on spe_k edges then 64->d/2, and
        // its own kNN Gram matrix.
        if (spe) AddMacs(cost, "spe", own * (64 + 64 * spe_k + 64 * d) + 3 * own * own);
        const int blocks = csa ? 2 : 0;  // the two self-attentions
        AddMacs(cost, "attention", blocks * Attention(own, keys(own), d));
        AddMacs(cost, "attention", Attention(own, keys(other), d));  // cross-attention
        // FPS of the anchors: 3 multiplies per point and chosen anchor, once per block's keys.
        if (!full) AddMacs(cost, "fps", (blocks + 1) * 3 * own * std::min(anchors, own));
        AddMacs(cost, "conv3_a", 8 * d * d * own);
        if (osp) AddMacs(cost, "overlap", own * OverlapHeadPerPoint(d));
        // GMM fit: FPS of J initial means, then per round point-mean distances and averages.
        const Int j = std::min(clusters, own);
        AddMacs(cost, "gmm_fit", 3 * own * j * (1 + 2 * rounds));
        AddMacs(cost, "cluster_features", own * j * d);
    }
    // Pair terms: the cosine matrix and the two pooled logits of the overlap head, the cluster
    // feature matching (cosines, matched means) and Kabsch's covariance.
    if (osp) AddMacs(cost, "overlap", n * m * d + 2 * n * m);
    const Int jp = std::min(clusters, n), jq = std::min(clusters, m);
    AddMacs(cost, "matching", jp * jq * d + jp * jq * 3 + 9 * jp);
    return cost;
}

/// regbench OGMM name prefix -> the authors' GMMReg name prefix. CONV(used='proj') is
/// net.{0 conv, 1 bn, 3 conv, 4 bn, 6 conv}; CONV(used=None) net.{0, 1, 3}.
const std::vector<std::pair<std::string, std::string>>& OgmmPrefixes() {
    static const std::vector<std::pair<std::string, std::string>> kPrefixes = [] {
        std::vector<std::pair<std::string, std::string>> v = {
            {"dgcnn.", "emd."},
            {"proj.conv1.", "proj.net.0."},
            {"proj.bn1.", "proj.net.1."},
            {"proj.conv2.", "proj.net.3."},
        };
        for (const auto& [rb, au] :
             std::vector<std::pair<std::string, std::string>>{{"conv3_o.", "overlap.net."},
                                                              {"conv3_a.", "conv1.net."},
                                                              {"conv3_b.", "conv2.net."}}) {
            v.emplace_back(rb + "conv1.", au + "0.");
            v.emplace_back(rb + "bn1.", au + "1.");
            v.emplace_back(rb + "conv2.", au + "3.");
            v.emplace_back(rb + "bn2.", au + "4.");
            v.emplace_back(rb + "conv3.", au + "6.");
        }
        v.emplace_back("spe.dist.", "pos.conv_dis.");
        v.emplace_back("spe.angle_2d.", "pos.conv_ang1.");
        v.emplace_back("spe.angle_1d.", "pos.conv_ang2.");
        v.emplace_back("spe.unused_conv.", "pos.conv.0.");
        v.emplace_back("spe.unused_bn.", "pos.conv.1.");
        for (const auto& [rb, au] : std::vector<std::pair<std::string, std::string>>{
                 {"att_s1.", "sattn1."}, {"att_c.", "cattn."}, {"att_s2.", "sattn2."}}) {
            v.emplace_back(rb + "merge.", au + "attn.merge.");
            v.emplace_back(rb + "proj.", au + "attn.proj.");
            v.emplace_back(rb + "mlp.", au + "mlp.");
        }
        return v;
    }();
    return kPrefixes;
}

/// The authors' GMMReg registers its modules in this order (its state_dict order).
int OgmmModuleRank(const std::string& authors_key) {
    static const char* kOrder[] = {"emd.", "proj.",   "overlap.", "conv1.", "conv2.",
                                   "pos.", "sattn1.", "cattn.",   "sattn2."};
    for (int j = 0; j < 9; ++j) {
        if (authors_key.rfind(kOrder[j], 0) == 0) return j;
    }
    return 9;
}

std::string OgmmAuthorsName(const std::string& rb) {
    for (const auto& [from, to] : OgmmPrefixes()) {
        if (rb.rfind(from, 0) == 0) return to + rb.substr(from.size());
    }
    throw std::logic_error("OGMM tensor " + rb + " has no counterpart in the authors' GMMReg");
}

/// The authors' GMMReg: emb_dims from emd.conv5; what no shape fixes from the import options.
nlohmann::json InferConfig(const StateDict& sd, const std::string& file,
                           const nlohmann::json& settings) {
    const torch::Tensor& conv5 =
        RequireAuthorsTensor(sd, "emd.conv5.weight", 4, file, "an OGMM GMMReg");
    const int64_t emb = conv5.size(0);
    const int64_t heads = settings.at("heads").get<int64_t>();
    if (heads < 1 || emb % 2 != 0 || emb % heads != 0) {
        RefuseAuthorsFile(file, "tensor emd.conv5.weight gives emb_dims " + std::to_string(emb) +
                                    ", which is not even or not divisible by " +
                                    std::to_string(heads) + " heads");
    }
    nlohmann::json c = Named("ogmm");
    const bool authors_defaults = emb == 512 && settings.at("clusters") == 128 &&
                                  settings.at("anchors") == 128 && heads == 4 &&
                                  settings.at("k") == 20;
    c["name"] = authors_defaults ? "ogmm" : "ogmm-authors";
    c["emb_dims"] = emb;
    for (const char* key : {"clusters", "anchors", "heads", "k"}) c[key] = settings.at(key);
    return c;
}

void CheckExport(const nlohmann::json& config, const std::string& where) {
    if (!config.value("spe", true) || !config.value("csa", true) || !config.value("osp", true)) {
        RefuseAuthorsFile(where,
                          "holds an OGMM ablation (spe/csa/osp off) whose modules the authors' "
                          "GMMReg does not match");
    }
}

}  // namespace

NetworkFamily OgmmFamily() {
    NetworkFamily f;
    f.arch = "ogmm";
    f.summary = "OGMM (Mei et al., WACV 2023): overlap-guided GMM registration";
    f.models = {"ogmm", "ogmm-small", "ogmm-tiny"};
    f.shipped_model = "ogmm";
    f.named_config = Named;
    BindConfig<OgmmConfig, OgmmNet>(f);
    f.forward_cost = OgmmCost;
    f.inference_params = {
        {"attention",
         "\"\" = the checkpoint's; \"clustered\" (FPS anchors) or \"full\" (every point, "
         "paper Tab. 6 \"f\") runs the checkpoint's weights with that attention (the two have "
         "the same parameters)",
         {"clustered", "full"}}};
    f.methods = {{"ogmm", true,
                  "OGMM network (LibTorch, CPU batch 1) + Open3D point-to-point ICP refinement",
                  "OGMM"},
                 {"ogmm-noicp", false, "OGMM network alone (LibTorch, CPU batch 1)"}};
    auto authors = std::make_shared<AuthorsFormat>();
    authors->module = "GMMReg (gfmei/ogmm models/gmmreg.py)";
    authors->infer_config = InferConfig;
    authors->authors_name = OgmmAuthorsName;
    authors->module_rank = OgmmModuleRank;
    authors->check_export = CheckExport;
    // The authors' mnet() defaults; no tensor shape fixes them.
    authors->settings = {{"clusters", 128, "GMM components J (the authors' n_clusters)"},
                         {"anchors", 128, "FPS anchors of the clustered attention (km_clusters)"},
                         {"heads", 4, "attention heads (num_heads)"},
                         {"k", 20, "DGCNN neighbours (gnn_k)"}};
    f.authors = std::move(authors);
    return f;
}

}  // namespace regbench::networks
