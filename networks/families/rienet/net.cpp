#include "networks/families/rienet/net.hpp"

#include <algorithm>
#include <set>
#include <stdexcept>

#include "networks/families/rienet/matching.hpp"
#include "networks/family_config.hpp"
#include "networks/layers/layers.hpp"

namespace regbench::networks {

namespace {

namespace nn = torch::nn;
using torch::indexing::Slice;

constexpr double kLeakySlope = 0.2;  // the discriminator's LeakyReLU (the authors' code)

nn::Conv2d Conv2dNoBias(int64_t in, int64_t out) {
    return nn::Conv2d(nn::Conv2dOptions(in, out, 1).bias(false));
}

/// Registers bias-free 1x1 Conv1d conv1..convK, then BatchNorm1d bn1..bnK (the authors' order)
/// on `m`: their PointNet and Pointer, which RIENET builds but never calls.
void RegisterUnusedChain(nn::Module& m, const std::vector<std::pair<int64_t, int64_t>>& widths) {
    for (size_t i = 0; i < widths.size(); ++i) {
        m.register_module(
            "conv" + std::to_string(i + 1),
            nn::Conv1d(nn::Conv1dOptions(widths[i].first, widths[i].second, 1).bias(false)));
    }
    for (size_t i = 0; i < widths.size(); ++i) {
        m.register_module("bn" + std::to_string(i + 1), nn::BatchNorm1d(widths[i].second));
    }
}

/// Conv2d (kernel (3, 1) along the neighbours, padded, or 1x1; with bias), BN2d, LeakyReLU.
void AddLeakyBlock(nn::Sequential& seq, int64_t in, int64_t out, bool along_neighbours) {
    nn::Conv2dOptions options(in, out, 1);
    if (along_neighbours) {
        options = nn::Conv2dOptions(in, out, torch::ExpandingArray<2>({3, 1}))
                      .padding(torch::ExpandingArray<2>({1, 0}));
    }
    seq->push_back(nn::Conv2d(options.bias(true)));
    seq->push_back(nn::BatchNorm2d(out));
    seq->push_back(nn::LeakyReLU(nn::LeakyReLUOptions().negative_slope(kLeakySlope)));
}

/// x [B, P, C], idx [B, Q, k] (values in [0, P)) -> [B, Q, k, C].
torch::Tensor GatherRows(const torch::Tensor& x, const torch::Tensor& idx) {
    const int64_t batch = x.size(0), points = x.size(1), channels = x.size(2);
    const torch::Tensor base = torch::arange(batch, idx.options()).view({-1, 1, 1}) * points;
    return x.reshape({batch * points, channels})
        .index_select(0, (idx + base).reshape({-1}))
        .view({batch, idx.size(1), idx.size(2), channels});
}

/// Offsets centre minus neighbour of rows x [B, N, C] over idx [B, N, k] -> [B, N, k, C].
torch::Tensor CentreMinusNeighbours(const torch::Tensor& x, const torch::Tensor& idx) {
    return x.unsqueeze(2) - GatherRows(x, idx);
}

/// Euclidean distances [B, N, M] of features f [B, N, C], g [B, M, C] from the Gram form,
/// negative rounding clamped to 0 with a zero gradient there (the authors' pairwise_distance).
/// Without autograd the clamp and root run in place (the same values, two N x M passes fewer).
torch::Tensor FeatureDistance(const torch::Tensor& f, const torch::Tensor& g) {
    const torch::Tensor norms = f.pow(2).sum(2, true) + g.pow(2).sum(2).unsqueeze(1);
    torch::Tensor d2 = torch::baddbmm(norms, f, g.transpose(1, 2), /*beta=*/1, /*alpha=*/-2);
    if (!torch::GradMode::is_enabled()) return d2.clamp_min_(0).sqrt_();
    const torch::Tensor zero = d2 <= 0;
    return torch::where(zero, torch::zeros_like(d2),
                        torch::sqrt(torch::where(zero, torch::ones_like(d2), d2)));
}

/// Sums of the non-self neighbours' rows: out[b, i, :] = sum over l = 1 .. k - 1 of
/// x[b, idx[b, i, l], :]. embedding_bag (mode sum) adds each bag's rows without materialising
/// the [N, k - 1, M] gather (index_select + sum was 2.6x slower).
torch::Tensor NeighbourRowSums(const torch::Tensor& x, const torch::Tensor& idx, int64_t k) {
    const int64_t batch = x.size(0), rows = x.size(1);
    const torch::Tensor base = torch::arange(batch, idx.options()).view({-1, 1, 1}) * rows;
    const torch::Tensor bags = (idx.index({Slice(), Slice(), Slice(1, k)}) + base).reshape(-1);
    const torch::Tensor offsets = torch::arange(0, bags.size(0), k - 1, idx.options());
    return std::get<0>(torch::embedding_bag(x.reshape({batch * rows, x.size(2)}), bags, offsets,
                                            false, /*mode=sum*/ 0))
        .view({batch, idx.size(1), x.size(2)});
}

/// Neighbourhood consensus nc[i, j] = sum over the non-self neighbours a of source point i and
/// l of target point j (the first k - 1 after the point itself) of scores[a, l], / (k - 1).
/// The column side runs on the transpose.
torch::Tensor Consensus(const torch::Tensor& scores, const torch::Tensor& idx_s,
                        const torch::Tensor& idx_t, int64_t k) {
    const torch::Tensor rows = NeighbourRowSums(scores, idx_s, k);                   // [B, N, M]
    const torch::Tensor cols = NeighbourRowSums(rows.transpose(1, 2).contiguous(), idx_t, k);
    return cols.div_(static_cast<double>(k - 1)).transpose(1, 2).contiguous();
}

/// The refined matching map softmax_j(-exp(margin - nc) d) from the feature distances d
/// [B, N, M]: with autograd the LibTorch composition; without, the fused row kernel
/// (networks/families/rienet/matching.hpp) over d's own storage, which it overwrites.
torch::Tensor RefinedMatching(torch::Tensor distance, const torch::Tensor& idx_s,
                              const torch::Tensor& idx_t, int64_t k_nc, double margin) {
    if (torch::GradMode::is_enabled()) {
        const torch::Tensor nc = Consensus(torch::softmax(-distance, 2), idx_s, idx_t, k_nc);
        return torch::softmax(-torch::exp(margin - nc) * distance, 2);
    }
    distance = distance.contiguous();
    const int64_t batch = distance.size(0), n = distance.size(1), m = distance.size(2);
    // Runs `kernel(item, first row, rows)` over the batch's rows, split across LibTorch's threads.
    const auto over_rows = [batch, n](const auto& kernel) {
        at::parallel_for(0, batch * n, 64, [&](int64_t begin, int64_t end) {
            while (begin < end) {  // row runs within one batch item
                const int64_t row = begin % n, count = std::min(end - begin, n - row);
                kernel(begin / n, begin, count);
                begin += count;
            }
        });
    };
    torch::Tensor scores = torch::empty_like(distance);
    AT_DISPATCH_FLOATING_TYPES(distance.scalar_type(), "rienet_scores", [&] {
        const scalar_t* d = distance.data_ptr<scalar_t>();
        scalar_t* s = scores.data_ptr<scalar_t>();
        over_rows([&](int64_t, int64_t first, int64_t count) {
            MatchingScoreRows(d + first * m, s + first * m, count, m);
        });
    });
    const torch::Tensor rows = NeighbourRowSums(scores, idx_s, k_nc).contiguous();
    scores = torch::Tensor();  // its memory is free for the next allocation
    const torch::Tensor cols = idx_t.contiguous();
    const int64_t stride = cols.size(2);
    AT_DISPATCH_FLOATING_TYPES(distance.scalar_type(), "rienet_refine", [&] {
        scalar_t* d = distance.data_ptr<scalar_t>();
        const scalar_t* r = rows.data_ptr<scalar_t>();
        const int64_t* c = cols.data_ptr<int64_t>();
        over_rows([&](int64_t item, int64_t first, int64_t count) {
            RefineMatchingRows(d + first * m, r + first * m, c + item * m * stride, count, m,
                               stride, k_nc, margin);
        });
    });
    return distance;
}

/// Weighted Kabsch: rows src, dst [B, N, 3], weights w [B, N] -> {R [B, 3, 3], t [B, 3]} with
/// dst ~ R src + t (the authors' compute_rigid_transformation).
std::pair<torch::Tensor, torch::Tensor> WeightedKabsch(const torch::Tensor& src,
                                                       const torch::Tensor& dst,
                                                       const torch::Tensor& w) {
    const torch::Tensor ww = w.unsqueeze(2), total = w.sum(1, true);
    const torch::Tensor cs = (src * ww).sum(1) / total, cd = (dst * ww).sum(1) / total;
    const torch::Tensor h =
        torch::bmm(((src - cs.unsqueeze(1)) * ww).transpose(1, 2), dst - cd.unsqueeze(1));
    const auto [u, s, vh] = torch::linalg_svd(h);
    const torch::Tensor v = vh.transpose(1, 2), ut = u.transpose(1, 2);
    const torch::Tensor det = torch::det(torch::bmm(v, ut));
    const torch::Tensor one = torch::ones_like(det);
    const torch::Tensor r =
        torch::bmm(v * torch::stack({one, one, det}, 1).unsqueeze(1), ut);  // V diag(1,1,d) U^T
    return {r, cd - torch::bmm(r, cs.unsqueeze(2)).squeeze(2)};
}

/// The authors' GlobalAlignLoss: Huber (threshold c) of each point's squared distance to the
/// nearest point of the other cloud, summed over both directions and the batch.
torch::Tensor HuberChamfer(const torch::Tensor& a, const torch::Tensor& b, double c) {
    const torch::Tensor d2 =
        a.pow(2).sum(2, true) - 2 * torch::bmm(a, b.transpose(1, 2)) + b.pow(2).sum(2).unsqueeze(1);
    const auto huber = [c](const torch::Tensor& x) {
        return torch::where(x < c, 0.5 * x * x, c * x - 0.5 * c * c).sum();
    };
    return huber(std::get<0>(d2.min(2))) + huber(std::get<0>(d2.min(1)));
}

void CheckCloud(const torch::Tensor& x, const char* which, int64_t batch, int64_t min_points) {
    if (!x.defined() || x.dim() != 3 || x.size(2) != 3 || (batch >= 0 && x.size(0) != batch)) {
        throw std::invalid_argument(std::string("rienet: ") + which +
                                    " must be a [B, N, 3] tensor" +
                                    (batch >= 0 ? " with the source's batch size" : ""));
    }
    if (x.size(1) < min_points) {
        throw std::invalid_argument(std::string("rienet: ") + which + " has " +
                                    std::to_string(x.size(1)) + " points, needs at least " +
                                    std::to_string(min_points) + " (k and k_nc neighbours)");
    }
}

}  // namespace

// Ranges (issues 44 and 55: a checkpoint's absurd sizes are refused before anything is
// built): 8 to 16 times the authors' values (emb_dims 256, dim 8 or 16, keypoints 256, k 5, 3
// iterations); dim 65536, within the old bound of 2^16, asked for 103 GB.
void RienetConfig::Validate(ParamCheck& c) const {
    InRange(c, "emb_dims", emb_dims, 1, 2048);
    InRange(c, "dim", dim, 1, 256);
    InRange(c, "iterations", iterations, 1, 32);
    InRange(c, "k", k, 2, 64);
    InRange(c, "k_nc", k_nc, 2, 64);
    NonNegative(c, "nn_margin", nn_margin);
    Positive(c, "loss_margin", loss_margin);
    InRange(c, "keypoints", keypoints, 1, 4096);
}

nlohmann::json ToJson(const RienetConfig& c) { return NetConfigJson(c, "rienet"); }

RienetConfig RienetConfigFromJson(const nlohmann::json& j) {
    return ParseNetConfig<RienetConfig>(j, "rienet");
}

RienetDgcnnImpl::RienetDgcnnImpl(int64_t emb_dims) {
    const std::pair<int64_t, int64_t> widths[] = {
        {3, 32}, {32, 32}, {32, 64}, {64, 128}, {256, emb_dims}};
    for (size_t i = 0; i < 5; ++i) {
        convs_.push_back(register_module("conv" + std::to_string(i + 1),
                                         Conv2dNoBias(widths[i].first, widths[i].second)));
    }
    for (size_t i = 0; i < 5; ++i) {
        bns_.push_back(
            register_module("bn" + std::to_string(i + 1), nn::BatchNorm2d(widths[i].second)));
    }
}

torch::Tensor RienetDgcnnImpl::forward(const torch::Tensor& xyz, const torch::Tensor& idx) {
    const int64_t batch = xyz.size(0), points = xyz.size(1), k = idx.size(2);
    // Channels last, one row per edge: neighbour minus centre (the authors' relative_coordinates).
    const torch::Tensor rows = (-CentreMinusNeighbours(xyz, idx)).reshape({-1, 3});
    const torch::Tensor cat = PooledEdgeStages(
        rows,
        {{convs_[0], bns_[0]}, {convs_[1], bns_[1]}, {convs_[2], bns_[2]}, {convs_[3], bns_[3]}},
        k);  // [B N, 256]
    return RowsConvBnRelu(cat, convs_[4], bns_[4]).view({batch, points, -1});
}

InlierDiscriminatorImpl::InlierDiscriminatorImpl(int64_t dim) {
    model1_ = register_module("model1", nn::Sequential());
    AddLeakyBlock(model1_, 3, dim, true);
    AddLeakyBlock(model1_, dim, 2 * dim, true);
    model2_ = register_module("model2", nn::Sequential());
    model3_ = register_module("model3", nn::Sequential());
    for (auto* seq : {&model2_, &model3_}) {
        AddLeakyBlock(*seq, 2 * dim, 16, false);
        AddLeakyBlock(*seq, 16, 16, false);
    }
    model4_ = register_module(
        "model4", nn::Sequential(nn::Conv1d(nn::Conv1dOptions(16, 8, 1)), nn::BatchNorm1d(8),
                                 nn::LeakyReLU(nn::LeakyReLUOptions().negative_slope(kLeakySlope)),
                                 nn::Conv1d(nn::Conv1dOptions(8, 1, 1))));
}

torch::Tensor InlierDiscriminatorImpl::forward(const torch::Tensor& pseudo,
                                               const torch::Tensor& source) {
    // [B, N, k, 3] -> [B, 3, k, N]: the (3, 1) kernels run along the neighbours, in their
    // order (nearest first); back to [B, C, N, k].
    const auto local = [this](const torch::Tensor& x) {
        return model1_->forward(x.permute({0, 3, 2, 1})).permute({0, 1, 3, 2});
    };
    const torch::Tensor diff = local(pseudo) - local(source);
    const torch::Tensor attention = torch::softmax(model3_->forward(diff), 3);
    const torch::Tensor pooled = (model2_->forward(diff) * attention).sum(3);  // [B, 16, N]
    return 1 - torch::tanh(model4_->forward(pooled).abs()).squeeze(1);
}

RienetNet::RienetNet(const RienetConfig& config) : config_(config) {
    auto emb_nn = register_module("emb_nn", std::make_shared<nn::Module>());
    dgcnn_ = emb_nn->register_module("model", RienetDgcnn(config_.emb_dims));
    auto point_embed = register_module("single_point_embed", std::make_shared<nn::Module>());
    RegisterUnusedChain(*point_embed, {{3, 32}, {32, 32}, {32, 64}, {64, 128}, {128, 256}});
    auto forwards = register_module("forwards", std::make_shared<nn::Module>());
    discriminator_ = forwards->register_module("weight_function", InlierDiscriminator(config_.dim));
    auto fuse = forwards->register_module("fuse", std::make_shared<nn::Module>());
    RegisterUnusedChain(*fuse, {{512, 256}, {256, 64}, {64, 32}});
}

// One iteration of the authors' SVDHead, in their order, reads best as one piece beside model.py;
// the blocks it is made of have names above. What their loss terms need is kept in `aux` (per
// iteration i: "moved_i", "corr_i", "pseudo_local_i", "weight_i", "neighbours_i",
// "matching_i"); Loss computes the terms from it, so an inference forward does not.
NetOutput RienetNet::Forward(const PairBatch& batch) {
    const int64_t k = config_.k, k_nc = config_.k_nc, k_max = std::max(k, k_nc);
    CheckCloud(batch.source, "source", -1, k_max);
    CheckCloud(batch.target, "target", batch.source.size(0), k_max);
    const torch::Tensor target = batch.target;
    torch::Tensor source = batch.source;
    const int64_t b = source.size(0);
    const torch::Tensor idx_t = KnnIndices(target.transpose(1, 2), k_max);  // [B, M, k_max]
    const torch::Tensor nbr_t = idx_t.index({Slice(), Slice(), Slice(0, k)});
    torch::Tensor target_features;
    torch::Tensor R = torch::eye(3, source.options()).expand({b, 3, 3});
    torch::Tensor t = torch::zeros({b, 3}, source.options());
    NetOutput out;
    for (int it = 0; it < config_.iterations; ++it) {
        const torch::Tensor idx_s = KnnIndices(source.transpose(1, 2), k_max);
        const torch::Tensor nbr_s = idx_s.index({Slice(), Slice(), Slice(0, k)});
        const torch::Tensor source_features = dgcnn_->forward(source, nbr_s);
        if (!target_features.defined() || is_training()) {
            target_features = dgcnn_->forward(target, nbr_t);
        }
        // Matching map refinement: point-wise map, neighbourhood consensus, refined map.
        const torch::Tensor distance = FeatureDistance(source_features, target_features);
        const torch::Tensor matching =
            RefinedMatching(distance, idx_s, idx_t, k_nc, config_.nn_margin);
        const torch::Tensor corr = torch::bmm(matching, target);  // pseudo targets [B, N, 3]
        // Inlier evaluation on the two neighbourhoods, then the weighted SVD.
        const torch::Tensor pseudo_local = CentreMinusNeighbours(corr, nbr_s);
        const torch::Tensor weight =
            discriminator_->forward(pseudo_local, CentreMinusNeighbours(source, nbr_s));
        const auto [R_i, t_i] = WeightedKabsch(source, corr, weight);
        const torch::Tensor moved = torch::bmm(source, R_i.transpose(1, 2)) + t_i.unsqueeze(1);
        const std::string n = std::to_string(it);
        out.aux["moved_" + n] = moved;
        out.aux["corr_" + n] = corr;
        out.aux["pseudo_local_" + n] = pseudo_local;
        out.aux["weight_" + n] = weight;
        out.aux["neighbours_" + n] = nbr_s;
        out.aux["matching_" + n] = matching;
        R = torch::bmm(R_i, R);
        t = torch::bmm(R_i, t.unsqueeze(2)).squeeze(2) + t_i;
        source = moved;
    }
    out.T = torch::eye(4, source.options()).repeat({b, 1, 1});
    out.T.index_put_({Slice(), Slice(0, 3), Slice(0, 3)}, R);
    out.T.index_put_({Slice(), Slice(0, 3), 3}, t);
    return out;
}

// The authors' loss terms, each summed over the iterations: on the keypoints of highest inlier
// weight the spatial consistency and the neighbourhood consensus, and the Huber chamfer of the
// moved source against the target.
LossTerms RienetNet::Loss(const PairBatch& batch, const NetOutput& output) {
    const torch::Tensor& target = batch.target;
    torch::Tensor global_alignment = torch::zeros({}, target.options());
    torch::Tensor consensus = torch::zeros({}, target.options());
    torch::Tensor spatial = torch::zeros({}, target.options());
    for (int it = 0; it < config_.iterations; ++it) {
        const std::string n = std::to_string(it);
        const auto get = [&output, &n](const char* name) -> const torch::Tensor& {
            const auto found = output.aux.find(name + n);
            if (found == output.aux.end()) {
                throw std::invalid_argument(std::string("rienet loss: the forward output has no ") +
                                            name + n);
            }
            return found->second;
        };
        const torch::Tensor& moved = get("moved_");
        const torch::Tensor& corr = get("corr_");
        const torch::Tensor& weight = get("weight_");
        const int64_t keypoints = std::min<int64_t>(config_.keypoints, weight.size(1));
        const torch::Tensor kp = std::get<1>(weight.topk(keypoints, 1)).unsqueeze(2);  // [B,K,1]
        const auto pick = [&kp](const torch::Tensor& x) {  // [B, N, ...] -> [B, K, ...]
            return GatherRows(x.flatten(2), kp).squeeze(2);
        };
        spatial = spatial - torch::log(std::get<0>(pick(get("matching_")).max(2)) + 1e-15).mean();
        const torch::Tensor keypoint_loss = (pick(moved) - pick(corr)).pow(2).sum();
        const torch::Tensor knn_loss =
            (pick(CentreMinusNeighbours(moved, get("neighbours_"))) - pick(get("pseudo_local_")))
                .pow(2)
                .sum();
        consensus = consensus + knn_loss / static_cast<double>(config_.k_nc) + keypoint_loss;
        global_alignment = global_alignment + HuberChamfer(target, moved, config_.loss_margin);
    }
    LossTerms terms;
    terms["global_alignment"] = global_alignment;
    terms["consensus"] = consensus;
    terms["spatial_consistency"] = spatial;
    terms["total"] = global_alignment + consensus + spatial;
    return terms;
}

std::map<std::string, int64_t> RienetForwardMacs(const RienetConfig& c, int64_t n, int64_t m) {
    const int64_t e = c.emb_dims, d = c.dim, k = c.k, its = c.iterations;
    // Light DGCNN per point: k edges through 3->32->32->64->128, then 256 -> emb.
    const auto dgcnn = [&](int64_t points) {
        return points * (k * (3 * 32 + 32 * 32 + 32 * 64 + 64 * 128) + 256 * e);
    };
    // Discriminator per point: model1 (kernel 3) on both neighbourhoods, model2 and model3 on
    // the difference, model4 on the pooled features.
    const int64_t disc_point =
        2 * k * (3 * 3 * d + 3 * d * 2 * d) + 2 * k * (2 * d * 16 + 16 * 16) + 16 * 8 + 8;
    std::map<std::string, int64_t> parts;
    parts["dgcnn"] = its * dgcnn(n) + dgcnn(m);         // the target's features once (eval mode)
    parts["matching"] = its * (n * m * e + 3 * n * m);  // Gram of features; pseudo targets
    parts["discriminator"] = its * n * disc_point;
    parts["svd"] = its * (9 * n + 9 * n);  // weighted covariance; moving the source
    int64_t total = 0;
    for (const auto& [part, macs] : parts) total += macs;
    parts["total"] = total;
    return parts;
}

}  // namespace regbench::networks
