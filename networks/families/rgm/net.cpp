#include "networks/families/rgm/net.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/params.hpp"
#include "networks/layers/layers.hpp"
#include "networks/families/rgm/assignment.hpp"
#include "networks/families/rgm/kernels.hpp"

namespace regbench::networks {

namespace {

namespace nn = torch::nn;
using torch::indexing::Slice;

/// The instance norm's epsilon (nn.InstanceNorm2d's default) and the LayerNorm's (the authors').
constexpr double kInstanceNormEps = 1e-5;
constexpr double kLayerNormEps = 1e-6;
/// The authors' SVDslover adds this to the sum of the weights before normalising them.
constexpr double kSvdWeightEps = 1e-5;
/// A test-time step with fewer matched pairs leaves the cloud where it is.
constexpr double kMinPairs = 3.0;

nn::Conv2d Conv(int64_t in, int64_t out) {
    return nn::Conv2d(nn::Conv2dOptions(in, out, 1).bias(false));
}

std::shared_ptr<nn::Module> Holder() { return std::make_shared<nn::Module>(); }

/// x W^T + b on [B, P, in] rows.
torch::Tensor Apply(nn::Linear l, const torch::Tensor& x) { return l->forward(x); }

void CheckClouds(const PairBatch& batch) {
    const torch::Tensor& s = batch.source;
    const torch::Tensor& t = batch.target;
    if (!s.defined() || !t.defined() || s.dim() != 3 || t.dim() != 3 || s.size(2) != 3 ||
        t.size(2) != 3 || s.size(0) != t.size(0) || s.size(1) < 1 || t.size(1) < 1) {
        throw std::invalid_argument(
            "rgm: source and target must be [B, N, 3] and [B, M, 3] with N, M >= 1");
    }
}

/// The 4 x 4 transforms [B, 4, 4] of rotations [B, 3, 3] and translations [B, 3].
torch::Tensor Homogeneous(const torch::Tensor& R, const torch::Tensor& t) {
    torch::Tensor T = torch::eye(4, R.options()).repeat({R.size(0), 1, 1});
    T.index_put_({Slice(), Slice(0, 3), Slice(0, 3)}, R);
    T.index_put_({Slice(), Slice(0, 3), 3}, t);
    return T;
}

/// Points [B, P, 3] moved by T [B, 4, 4].
torch::Tensor Move(const torch::Tensor& points, const torch::Tensor& T) {
    return torch::bmm(points, T.index({Slice(), Slice(0, 3), Slice(0, 3)}).transpose(1, 2)) +
           T.index({Slice(), Slice(0, 3), 3}).unsqueeze(1);
}

/// Identity where a batch entry has fewer than kMinPairs pairs (pair counts [B]).
torch::Tensor IdentityWhereFew(const torch::Tensor& T, const torch::Tensor& pairs) {
    const torch::Tensor few = (pairs < kMinPairs).view({-1, 1, 1});
    return torch::where(few, torch::eye(4, T.options()).expand_as(T), T);
}

/// softmax(scale x, -1) for scale > 0 by the fused row kernel (networks/families/rgm/kernels.hpp)
/// over x's own storage, which it overwrites (when contiguous); no autograd.
torch::Tensor ScaledSoftmaxInPlace(torch::Tensor x, double scale) {
    x = x.contiguous();
    const int64_t m = x.size(-1);
    AT_DISPATCH_FLOATING_TYPES(x.scalar_type(), "rgm_softmax", [&] {
        ScaledSoftmaxRows(x.data_ptr<scalar_t>(), x.numel() / m, m, scale, nullptr);
    });
    return x;
}

}  // namespace

// Ranges: the authors run k 20, 4 heads, 20 Sinkhorn iterations and 2 estimate rounds at their
// full widths (divisor 1); the bounds are 6 to 50 times those.
void RgmConfig::Validate(ParamCheck& c) const {
    InRange(c, "width_divisor", width_divisor, 1, 64);
    c.Require(width_divisor >= 1 && 64 % width_divisor == 0, "width_divisor",
              "must divide 64 (1, 2, ..., 64), got " + std::to_string(width_divisor));
    InRange(c, "k", k, 1, 128);
    InRange(c, "heads", heads, 1, 64);
    if (width_divisor >= 1 && 64 % width_divisor == 0) {
        const RgmWidths w(width_divisor);
        c.Require(w.gnn % heads == 0 && (w.node + w.edge) % heads == 0, "heads",
                  "must divide the widths " + std::to_string(w.node + w.edge) + " and " +
                      std::to_string(w.gnn) + ", got " + std::to_string(heads));
    }
    InRange(c, "sinkhorn_iterations", sinkhorn_iterations, 1, 1000);
    InRange(c, "estimate_iterations", estimate_iterations, 1, 32);
    NonNegative(c, "inlier_threshold", inlier_threshold);
    Positive(c, "label_dist", label_dist);
}

nlohmann::json ToJson(const RgmConfig& c) { return NetConfigJson(c, "rgm"); }

RgmConfig RgmConfigFromJson(const nlohmann::json& j) { return ParseNetConfig<RgmConfig>(j, "rgm"); }

RgmWidths::RgmWidths(int d)
    : c1(64 / d),
      c2(64 / d),
      c3(128 / d),
      c4(256 / d),
      node(c1 + c2 + c3 + c4),
      edge(512 / d),
      gnn(512 / d),
      ff(1024 / d) {}

// ---- transformer -----------------------------------------------------------------------------

RgmAttentionImpl::RgmAttentionImpl(int64_t d, int64_t heads) : heads_(heads) {
    linears_ = register_module("linears", nn::ModuleList());
    for (int i = 0; i < 4; ++i) linears_->push_back(nn::Linear(d, d));
}

torch::Tensor RgmAttentionImpl::forward(const torch::Tensor& x, const torch::Tensor& memory) {
    const int64_t B = x.size(0), P = x.size(1), Q = memory.size(1), d = x.size(2);
    const int64_t dk = d / heads_;
    const auto project = [&](int i, const torch::Tensor& in, int64_t n) {
        return linears_->ptr<nn::LinearImpl>(i)->forward(in).view({B, n, heads_, dk}).transpose(1, 2);
    };
    const torch::Tensor q = project(0, x, P), k = project(1, memory, Q), v = project(2, memory, Q);
    const torch::Tensor scores = torch::matmul(q, k.transpose(2, 3));
    const double root = std::sqrt(static_cast<double>(dk));
    const torch::Tensor p = torch::GradMode::is_enabled()
                                ? torch::softmax(scores / root, -1)
                                : ScaledSoftmaxInPlace(scores, 1.0 / root);
    const torch::Tensor o = torch::matmul(p, v).transpose(1, 2).reshape({B, P, d});
    return linears_->ptr<nn::LinearImpl>(3)->forward(o);
}

RgmLayerNormImpl::RgmLayerNormImpl(int64_t d) {
    a_2_ = register_parameter("a_2", torch::ones({d}));
    b_2_ = register_parameter("b_2", torch::zeros({d}));
}

torch::Tensor RgmLayerNormImpl::forward(const torch::Tensor& x) {
    if (!torch::GradMode::is_enabled()) {  // the fused row kernel (kernels.hpp)
        const torch::Tensor in = x.contiguous();
        const torch::Tensor a = a_2_.contiguous(), b = b_2_.contiguous();
        torch::Tensor out = torch::empty_like(in);
        const int64_t d = in.size(-1);
        AT_DISPATCH_FLOATING_TYPES(in.scalar_type(), "rgm_layer_norm", [&] {
            LayerNormRows(in.data_ptr<scalar_t>(), out.data_ptr<scalar_t>(), in.numel() / d, d,
                          a.data_ptr<scalar_t>(), b.data_ptr<scalar_t>(), kLayerNormEps);
        });
        return out;
    }
    const torch::Tensor mean = x.mean(-1, true);
    const torch::Tensor std = x.std(-1, /*unbiased=*/true, /*keepdim=*/true);
    return a_2_ * (x - mean) / (std + kLayerNormEps) + b_2_;
}

namespace {

torch::Tensor FeedForward(RgmTransformerLayer& t, const torch::Tensor& x) {
    return t.w_2->forward(t.w_1->forward(x).relu());
}

/// Builds "layers.0.{self_attn, [src_attn,] feed_forward.{w_1, w_2}, sublayer.I.norm}" and
/// "norm" on `stack` (the authors' Encoder or Decoder of one layer).
RgmTransformerLayer BuildLayer(nn::Module& stack, int64_t d, int64_t ff, int64_t heads,
                               bool decoder) {
    RgmTransformerLayer t;
    auto layers = stack.register_module("layers", nn::ModuleList());
    auto layer = Holder();
    t.self_attn = layer->register_module("self_attn", RgmAttention(d, heads));
    if (decoder) t.src_attn = layer->register_module("src_attn", RgmAttention(d, heads));
    auto feed = layer->register_module("feed_forward", Holder());
    t.w_1 = feed->register_module("w_1", nn::Linear(d, ff));
    t.w_2 = feed->register_module("w_2", nn::Linear(ff, d));
    auto sub = layer->register_module("sublayer", nn::ModuleList());
    for (int i = 0; i < (decoder ? 3 : 2); ++i) {
        auto s = Holder();
        t.norms.push_back(s->register_module("norm", RgmLayerNorm(d)));
        sub->push_back(s);
    }
    layers->push_back(layer);
    t.final_norm = stack.register_module("norm", RgmLayerNorm(d));
    return t;
}

}  // namespace

RgmTransformerImpl::RgmTransformerImpl(int64_t d, int64_t ff, int64_t heads) {
    auto model = register_module("model", Holder());
    encoder_ = BuildLayer(*model->register_module("encoder", Holder()), d, ff, heads, false);
    decoder_ = BuildLayer(*model->register_module("decoder", Holder()), d, ff, heads, true);
}

std::pair<torch::Tensor, torch::Tensor> RgmTransformerImpl::forward(const torch::Tensor& src,
                                                                    const torch::Tensor& tgt) {
    // Pre-norm residual sublayers; the memory is the encoder's output (after its norm).
    const auto encode = [&](const torch::Tensor& x) {
        RgmTransformerLayer& e = encoder_;
        const torch::Tensor n0 = e.norms[0]->forward(x);
        torch::Tensor h = x + e.self_attn->forward(n0, n0);
        h = h + FeedForward(e, e.norms[1]->forward(h));
        return e.final_norm->forward(h);
    };
    const auto decode = [&](const torch::Tensor& y, const torch::Tensor& memory) {
        RgmTransformerLayer& e = decoder_;
        const torch::Tensor n0 = e.norms[0]->forward(y);
        torch::Tensor h = y + e.self_attn->forward(n0, n0);
        h = h + e.src_attn->forward(e.norms[1]->forward(h), memory);
        h = h + FeedForward(e, e.norms[2]->forward(h));
        return e.final_norm->forward(h);
    };
    const torch::Tensor tgt_embedding = decode(tgt, encode(src)).transpose(1, 2);
    const torch::Tensor src_embedding = decode(src, encode(tgt)).transpose(1, 2);
    return {src_embedding, tgt_embedding};
}

// ---- the network -----------------------------------------------------------------------------

RgmNet::RgmNet(const RgmConfig& config) : config_(config) {
    const RgmWidths w(config.width_divisor);
    auto features = register_module("pointfeaturer", Holder());
    const std::vector<std::pair<int64_t, int64_t>> io = {
        {6, w.c1}, {w.c1, w.c2}, {w.c2, w.c3}, {w.c3, w.c4}, {w.node, w.edge}};
    for (size_t i = 0; i < io.size(); ++i) {
        convs_.push_back(features->register_module("conv" + std::to_string(i + 1),
                                                   Conv(io[i].first, io[i].second)));
    }
    for (size_t i = 0; i < io.size(); ++i) {
        bns_.push_back(features->register_module("bn" + std::to_string(i + 1),
                                                 nn::BatchNorm2d(io[i].second)));
    }
    for (int i = 0; i < 2; ++i) {
        const std::string n = std::to_string(i);
        const int64_t in = i == 0 ? w.node + w.edge : w.gnn;
        auto gnn = register_module("gnn_layer_" + n, Holder());
        auto gconv = gnn->register_module("gconv", Holder());
        a_fc_.push_back(gconv->register_module("a_fc", nn::Linear(in, w.gnn)));
        u_fc_.push_back(gconv->register_module("u_fc", nn::Linear(in, w.gnn)));
        auto affinity = register_module("affinity_" + n, Holder());
        // The authors' init: uniform(+-1/sqrt(d)) + identity.
        const double stdv = 1.0 / std::sqrt(static_cast<double>(w.gnn));
        affinity_.push_back(affinity->register_parameter(
            "A", torch::rand({w.gnn, w.gnn}) * (2 * stdv) - stdv + torch::eye(w.gnn)));
        transformers_.push_back(
            register_module("gmattend" + n, RgmTransformer(in, w.ff, config.heads)));
        auto norm = register_module("InstNorm_layer_" + n, Holder());
        norm_weight_.push_back(norm->register_parameter("weight", torch::ones({1})));
        norm_bias_.push_back(norm->register_parameter("bias", torch::zeros({1})));
        if (i == 0) cross_graph_ = register_module("cross_graph_0", nn::Linear(2 * w.gnn, w.gnn));
    }
}

torch::Tensor RgmNet::Features(const torch::Tensor& points) {
    const int64_t B = points.size(0), P = points.size(1);
    const int64_t k = std::min<int64_t>(config_.k, P);
    const torch::Tensor x = points.transpose(1, 2).contiguous();  // [B, 3, P]
    const torch::Tensor idx = KnnIndices(x, k);                   // [B, P, k]
    const torch::Tensor base = torch::arange(B, idx.options()).view({B, 1, 1}) * P;
    const torch::Tensor flat = points.reshape({B * P, 3});
    const torch::Tensor neighbours = flat.index_select(0, (idx + base).view(-1));  // [B P k, 3]
    const torch::Tensor centres =
        points.unsqueeze(2).expand({B, P, k, 3}).reshape({B * P * k, 3});
    const torch::Tensor rows = torch::cat({neighbours, centres}, 1);  // [x_j, x_i]
    std::vector<std::pair<nn::Conv2d, nn::BatchNorm2d>> stages;
    for (int i = 0; i < 4; ++i) stages.emplace_back(convs_[i], bns_[i]);
    const torch::Tensor node = PooledEdgeStages(rows, stages, k);  // [B P, node]
    const torch::Tensor edge = RowsConvBnRelu(node, convs_[4], bns_[4]);
    return torch::cat({node, edge}, 1).view({B, P, -1});
}

torch::Tensor SinkhornSlack(const torch::Tensor& log_alpha, int iterations) {
    const int64_t N = log_alpha.size(1), M = log_alpha.size(2);
    torch::Tensor la = torch::constant_pad_nd(log_alpha, {0, 1, 0, 1}, 0.0);
    for (int i = 0; i < iterations; ++i) {
        const torch::Tensor rows = la.narrow(1, 0, N);
        la = torch::cat({rows - torch::logsumexp(rows, {2}, true), la.narrow(1, N, 1)}, 1);
        const torch::Tensor cols = la.narrow(2, 0, M);
        la = torch::cat({cols - torch::logsumexp(cols, {1}, true), la.narrow(2, M, 1)}, 2);
    }
    return la.narrow(1, 0, N).narrow(2, 0, M);
}

torch::Tensor SinkhornSlackExpInPlace(torch::Tensor log_alpha, int iterations) {
    if (torch::GradMode::is_enabled()) return SinkhornSlack(log_alpha, iterations).exp();
    log_alpha = log_alpha.contiguous();
    const int64_t B = log_alpha.size(0), N = log_alpha.size(1), M = log_alpha.size(2);
    AT_DISPATCH_FLOATING_TYPES(log_alpha.scalar_type(), "rgm_sinkhorn", [&] {
        std::vector<scalar_t> work(static_cast<size_t>(N + 3 * M));
        scalar_t* l = log_alpha.data_ptr<scalar_t>();
        for (int64_t b = 0; b < B; ++b) {
            SinkhornSlackExp(l + b * N * M, N, M, iterations, work.data());
        }
    });
    return log_alpha;
}

torch::Tensor SoftAdjacency(torch::Tensor gram, double scale) {
    if (torch::GradMode::is_enabled()) {
        const torch::Tensor a = torch::softmax(gram * scale, -1);
        return a / a.sum(1, true).clamp_min(1e-12);
    }
    gram = gram.contiguous();
    const int64_t B = gram.size(0), P = gram.size(1), Q = gram.size(2);
    AT_DISPATCH_FLOATING_TYPES(gram.scalar_type(), "rgm_adjacency", [&] {
        std::vector<scalar_t> sums(static_cast<size_t>(Q));
        scalar_t* g = gram.data_ptr<scalar_t>();
        for (int64_t b = 0; b < B; ++b) {
            std::fill(sums.begin(), sums.end(), scalar_t(0));
            ScaledSoftmaxRows(g + b * P * Q, P, Q, scale, sums.data());
            DivideColumns(g + b * P * Q, P, Q, sums.data());
        }
    });
    return gram;
}

torch::Tensor RgmNet::Match(const torch::Tensor& source, const torch::Tensor& target) {
    torch::Tensor emb_src = Features(source), emb_tgt = Features(target);
    torch::Tensor s;
    for (int i = 0; i < 2; ++i) {
        const auto [src_e, tgt_e] = transformers_[i]->forward(emb_src, emb_tgt);  // [B, d, P]
        const double scale = 1.0 / std::sqrt(static_cast<double>(src_e.size(1)));
        // The soft adjacency, its columns then normalised to sum 1 (F.normalize p=1, dim -2).
        const auto adjacency = [&](const torch::Tensor& e) {
            return SoftAdjacency(torch::bmm(e.transpose(1, 2), e), scale);
        };
        const auto gconv = [&](const torch::Tensor& A, const torch::Tensor& x) {
            return torch::bmm(A, Apply(a_fc_[i], x).relu()) + Apply(u_fc_[i], x).relu();
        };
        emb_src = gconv(adjacency(src_e), emb_src);
        emb_tgt = gconv(adjacency(tgt_e), emb_tgt);
        const torch::Tensor A = (affinity_[i] + affinity_[i].t()) / 2;
        torch::Tensor aff = torch::bmm(torch::matmul(emb_src, A), emb_tgt.transpose(1, 2));
        // Instance norm over the N x M entries of each pair, affine.
        const torch::Tensor mean = aff.mean({1, 2}, true);
        const torch::Tensor var = aff.var({1, 2}, /*unbiased=*/false, /*keepdim=*/true);
        aff = (aff - mean) / torch::sqrt(var + kInstanceNormEps) * norm_weight_[i] +
              norm_bias_[i];
        s = SinkhornSlackExpInPlace(aff, config_.sinkhorn_iterations);
        if (i == 0) {
            const torch::Tensor src_new =
                Apply(cross_graph_, torch::cat({emb_src, torch::bmm(s, emb_tgt)}, 2));
            const torch::Tensor tgt_new =
                Apply(cross_graph_, torch::cat({emb_tgt, torch::bmm(s.transpose(1, 2), emb_src)}, 2));
            emb_src = src_new;
            emb_tgt = tgt_new;
        }
    }
    return s;
}

torch::Tensor WeightedRigid(const torch::Tensor& P, const torch::Tensor& Q, const torch::Tensor& w) {
    const torch::Tensor total = w.sum(1, true);
    const torch::Tensor wn = (w / (total + kSvdWeightEps)).unsqueeze(2);  // [B, N, 1]
    const torch::Tensor cp = (P * wn).sum(1), cq = (Q * wn).sum(1);       // [B, 3]
    const torch::Tensor cov =
        torch::bmm((P - cp.unsqueeze(1)).transpose(1, 2), (Q - cq.unsqueeze(1)) * wn);
    const auto [U, S, Vh] = torch::linalg_svd(cov, /*full_matrices=*/true);
    (void)S;
    const torch::Tensor V = Vh.transpose(1, 2);
    const torch::Tensor pos = torch::bmm(V, U.transpose(1, 2));
    const torch::Tensor flip = torch::tensor({1.0, 1.0, -1.0}, V.options());
    const torch::Tensor neg = torch::bmm(V * flip, U.transpose(1, 2));
    const torch::Tensor R = torch::where((torch::det(pos) > 0).view({-1, 1, 1}), pos, neg);
    const torch::Tensor t = cq - torch::bmm(R, cp.unsqueeze(2)).squeeze(2);
    const torch::Tensor T = Homogeneous(R, t);
    return torch::where((total > 0).view({-1, 1, 1}), T,
                        torch::eye(4, T.options()).expand_as(T));
}

torch::Tensor AssignInliers(const torch::Tensor& s, double threshold) {
    const torch::Tensor d = s.detach().to(torch::kCPU, torch::kDouble).contiguous();
    const torch::Tensor rows = torch::nonzero(d.sum(1) > threshold).view(-1);
    const torch::Tensor cols = torch::nonzero(d.sum(0) > threshold).view(-1);
    torch::Tensor perm = torch::zeros_like(d);
    if (rows.numel() == 0 || cols.numel() == 0) return perm;
    const torch::Tensor sub = d.index_select(0, rows).index_select(1, cols).contiguous();
    const std::vector<double> weights(sub.data_ptr<double>(), sub.data_ptr<double>() + sub.numel());
    const std::vector<int64_t> match = MaxWeightAssignment(weights, rows.numel(), cols.numel());
    const auto r = rows.accessor<int64_t, 1>();
    const auto c = cols.accessor<int64_t, 1>();
    auto p = perm.accessor<double, 2>();
    for (size_t i = 0; i < match.size(); ++i) {
        if (match[i] >= 0) p[r[static_cast<int64_t>(i)]][c[match[i]]] = 1.0;
    }
    return perm;
}

torch::Tensor RgmNet::Direction(const torch::Tensor& source, const torch::Tensor& target,
                                torch::Tensor* first) {
    torch::Tensor moved = source;
    torch::Tensor perm;
    for (int it = 0; it < config_.estimate_iterations; ++it) {
        const torch::Tensor s = Match(moved, target);
        if (it == 0 && first != nullptr) *first = s;
        std::vector<torch::Tensor> perms;
        for (int64_t b = 0; b < s.size(0); ++b) {
            perms.push_back(AssignInliers(s[b], config_.inlier_threshold));
        }
        perm = torch::stack(perms).to(s.options());
        if (it + 1 < config_.estimate_iterations) {
            const torch::Tensor w = perm.sum(2);
            const torch::Tensor T =
                IdentityWhereFew(WeightedRigid(moved, torch::bmm(perm, target), w), w.sum(1));
            moved = Move(moved, T);
        }
    }
    return perm;
}

NetOutput RgmNet::Forward(const PairBatch& batch) {
    CheckClouds(batch);
    const torch::Tensor& src = batch.source;
    const torch::Tensor& tgt = batch.target;
    NetOutput out;
    if (is_training()) {
        const torch::Tensor s = Match(src, tgt);
        out.aux["s"] = s;
        torch::NoGradGuard no_grad;
        const torch::Tensor w = s.sum(2);
        const torch::Tensor matched = torch::bmm(s, tgt) / w.clamp_min(1e-12).unsqueeze(2);
        out.T = WeightedRigid(src, matched, w);
        return out;
    }
    torch::NoGradGuard no_grad;
    torch::Tensor first;
    torch::Tensor perm = Direction(src, tgt, &first);
    if (config_.cycle) perm = perm * Direction(tgt, src).transpose(1, 2);
    const torch::Tensor w = perm.sum(2);
    out.T = IdentityWhereFew(WeightedRigid(src, torch::bmm(perm, tgt), w), w.sum(1));
    out.aux["correspondence"] = perm;
    out.aux["s"] = first;
    return out;
}

namespace {

/// The ground-truth correspondence [N, M] of source (moved by T_gt) and target rows
/// (RgmNet::Loss).
torch::Tensor GroundTruthCorrespondence(const torch::Tensor& moved, const torch::Tensor& target,
                                        double dist) {
    const torch::Tensor d = torch::cdist(moved.to(torch::kDouble), target.to(torch::kDouble));
    const int64_t N = d.size(0), M = d.size(1);
    const auto [ds, ns] = d.min(1);  // nearest target of each source point
    const auto [dt, nt] = d.min(0);  // nearest source of each target point
    const auto dsa = ds.accessor<double, 1>();
    const auto dta = dt.accessor<double, 1>();
    const auto nsa = ns.accessor<int64_t, 1>();
    const auto nta = nt.accessor<int64_t, 1>();
    torch::Tensor perm = torch::zeros({N, M}, torch::kDouble);
    auto p = perm.accessor<double, 2>();
    std::vector<char> row_used(static_cast<size_t>(N), 0), col_used(static_cast<size_t>(M), 0);
    const auto take = [&](int64_t i, int64_t j) {
        p[i][j] = 1.0;
        row_used[static_cast<size_t>(i)] = 1;
        col_used[static_cast<size_t>(j)] = 1;
    };
    for (int64_t i = 0; i < N; ++i) {
        if (nta[nsa[i]] == i && dsa[i] < dist) take(i, nsa[i]);
    }
    for (int64_t i = 0; i < N; ++i) {
        if (!row_used[static_cast<size_t>(i)] && !col_used[static_cast<size_t>(nsa[i])] &&
            dsa[i] < dist) {
            take(i, nsa[i]);
        }
    }
    for (int64_t j = 0; j < M; ++j) {
        if (!col_used[static_cast<size_t>(j)] && !row_used[static_cast<size_t>(nta[j])] &&
            dta[j] < dist) {
            take(nta[j], j);
        }
    }
    return perm;
}

}  // namespace

LossTerms RgmNet::Loss(const PairBatch& batch, const NetOutput& output) {
    if (!batch.T_gt.defined()) throw std::invalid_argument("rgm loss: the batch has no T_gt");
    if (!output.aux.count("s")) {
        throw std::invalid_argument("rgm loss: the output has no soft correspondence \"s\"");
    }
    const torch::Tensor& s = output.aux.at("s");
    const torch::Tensor moved = Move(batch.source, batch.T_gt.to(batch.source.dtype())).detach();
    std::vector<torch::Tensor> gts;
    for (int64_t b = 0; b < s.size(0); ++b) {
        gts.push_back(GroundTruthCorrespondence(moved[b].cpu(), batch.target[b].detach().cpu(),
                                                config_.label_dist));
    }
    const torch::Tensor gt = torch::stack(gts).to(s.options());
    const torch::Tensor bce =
        torch::binary_cross_entropy(s.clamp(0.0, 1.0), gt, {}, at::Reduction::Sum) /
        static_cast<double>(s.size(0) * s.size(1));
    return {{"perm", bce}, {"total", bce}};
}

std::map<std::string, int64_t> RgmForwardMacs(const RgmConfig& c, int64_t n, int64_t m) {
    const RgmWidths w(c.width_divisor);
    std::map<std::string, int64_t> macs;
    const auto pass = [&](int64_t a, int64_t b) {  // one match, source a, target b points
        for (const int64_t p : {a, b}) {
            const int64_t k = std::min<int64_t>(c.k, p);
            macs["dgcnn"] += p * k * (6 * w.c1 + w.c1 * w.c2 + w.c2 * w.c3 + w.c3 * w.c4) +
                             p * w.node * w.edge + 3 * p * p;
        }
        for (int i = 0; i < 2; ++i) {
            const int64_t d = i == 0 ? w.node + w.edge : w.gnn;
            const auto enc = [&](int64_t p) { return 4 * p * d * d + 2 * p * p * d + 2 * p * d * w.ff; };
            const auto dec = [&](int64_t p, int64_t q) {
                return 4 * p * d * d + 2 * p * p * d + 2 * p * d * d + 2 * q * d * d + 2 * p * q * d +
                       2 * p * d * w.ff;
            };
            macs["transformer"] += enc(a) + enc(b) + dec(a, b) + dec(b, a);
            macs["adjacency"] += (a * a + b * b) * d;
            macs["gconv"] += 2 * (a + b) * d * w.gnn + (a * a + b * b) * w.gnn;
            macs["affinity"] += a * w.gnn * w.gnn + a * b * w.gnn;
            if (i == 0) macs["cross_graph"] += 2 * a * b * w.gnn + (a + b) * 2 * w.gnn * w.gnn;
        }
    };
    for (int it = 0; it < c.estimate_iterations; ++it) {
        pass(n, m);
        if (c.cycle) pass(m, n);
    }
    return macs;
}

}  // namespace regbench::networks
