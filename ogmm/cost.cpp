#include "ogmm/cost.hpp"

#include <algorithm>
#include <stdexcept>

namespace regbench::ogmm {
namespace {

using Int = std::int64_t;

Int Key(const nlohmann::json& c, const char* key) {
    if (!c.contains(key)) {
        throw std::invalid_argument(std::string("forward cost: config has no \"") + key +
                                    "\": " + c.dump());
    }
    return c.at(key).get<Int>();
}

/// Static DGCNN on n points: edge convs 6->64->64->128->256 on n k edges, the 512 -> d conv per
/// point, and the kNN Gram matrix (3 n^2).
Int Dgcnn(Int n, Int k, Int d) {
    constexpr Int kEdgeMacs = 6 * 64 + 64 * 64 + 64 * 128 + 128 * 256;  // 45,440 per edge
    return n * k * kEdgeMacs + n * 512 * d + 3 * n * n;
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

void Add(ForwardCost& cost, const std::string& part, Int macs) {
    cost.parts[part] += macs;
    cost.total += macs;
}

ForwardCost OgmmCost(const nlohmann::json& c, Int n, Int m) {
    const Int d = Key(c, "emb_dims"), k = Key(c, "k"), spe_k = Key(c, "spe_k");
    const Int anchors = Key(c, "anchors"), clusters = Key(c, "clusters");
    const Int rounds = Key(c, "gmm_iterations");
    const bool spe = c.at("spe").get<bool>(), csa = c.at("csa").get<bool>();
    const bool osp = c.at("osp").get<bool>();
    const bool full = c.at("attention").get<std::string>() == "full";
    const auto keys = [&](Int points) { return full ? points : std::min(anchors, points); };
    ForwardCost cost;
    for (const auto& [own, other] : {std::pair<Int, Int>{n, m}, std::pair<Int, Int>{m, n}}) {
        Add(cost, "dgcnn", Dgcnn(own, k, d));
        // SPE: distance branch 1->64->d/2, angle branch 1->64 on spe_k edges then 64->d/2, and
        // its own kNN Gram matrix.
        if (spe) Add(cost, "spe", own * (64 + 64 * spe_k + 64 * d) + 3 * own * own);
        const int blocks = csa ? 2 : 0;  // the two self-attentions
        Add(cost, "attention", blocks * Attention(own, keys(own), d));
        Add(cost, "attention", Attention(own, keys(other), d));  // cross-attention
        // FPS of the anchors: 3 multiplies per point and chosen anchor, once per block's keys.
        if (!full) Add(cost, "fps", (blocks + 1) * 3 * own * std::min(anchors, own));
        Add(cost, "conv3_a", 8 * d * d * own);
        if (osp) Add(cost, "overlap", own * OverlapHeadPerPoint(d));
        // GMM fit: FPS of J initial means, then per round point-mean distances and averages.
        const Int j = std::min(clusters, own);
        Add(cost, "gmm_fit", 3 * own * j * (1 + 2 * rounds));
        Add(cost, "cluster_features", own * j * d);
    }
    // Pair terms: the cosine matrix and the two pooled logits of the overlap head, the cluster
    // feature matching (cosines, matched means) and Kabsch's covariance.
    if (osp) Add(cost, "overlap", n * m * d + 2 * n * m);
    const Int jp = std::min(clusters, n), jq = std::min(clusters, m);
    Add(cost, "matching", jp * jq * d + jp * jq * 3 + 9 * jp);
    return cost;
}

ForwardCost DeepGmrCost(const nlohmann::json& c, Int n, Int m) {
    const std::string features = c.at("features").get<std::string>();
    const Int j = Key(c, "clusters");
    ForwardCost cost;
    for (const Int own : {n, m}) {
        if (features == "dgcnn") {
            const Int d = Key(c, "emb_dims"), h = Key(c, "head_hidden");
            Add(cost, "dgcnn", Dgcnn(own, Key(c, "dgcnn_k"), d));
            Add(cost, "head", own * (d * h + h * h + h * j));
        } else {
            const Int d_in = features == "rri" ? 4 * Key(c, "rri_k") : 3;
            Add(cost, "pointnet_encoder", own * (d_in * 64 + 64 * 128 + 128 * 256 + 256 * 1024));
            Add(cost, "pointnet_decoder", own * (2048 * 512 + 512 * 256 + 256 * 128 + 128 * j));
        }
        // Mixture: weighted means (3 n J), squared distances (3 n J), variances (n J).
        Add(cost, "mixture", 7 * own * j);
    }
    Add(cost, "register", 2 * 9 * j);  // two weighted 3x3 covariances (T and T21)
    return cost;
}

}  // namespace

ForwardCost ComputeForwardCost(const nlohmann::json& config, std::int64_t source_points,
                               std::int64_t target_points) {
    if (source_points < 1 || target_points < 1) {
        throw std::invalid_argument("forward cost: point counts must be positive, got " +
                                    std::to_string(source_points) + " and " +
                                    std::to_string(target_points));
    }
    const std::string arch = config.value("arch", std::string("ogmm"));
    if (arch == "ogmm") return OgmmCost(config, source_points, target_points);
    if (arch == "deepgmr") return DeepGmrCost(config, source_points, target_points);
    throw std::invalid_argument("forward cost: unknown arch '" + arch + "'");
}

}  // namespace regbench::ogmm
