#include "networks/families/regtr/net.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

#include "core/kd_tree.hpp"
#include "networks/families/regtr/kernels.hpp"
#include "networks/family_config.hpp"
#include "networks/layers/attention_rows.hpp"
#include "networks/layers/layers.hpp"

namespace regbench::networks {

namespace {

namespace nn = torch::nn;
namespace F = torch::nn::functional;
using torch::indexing::Slice;

constexpr double kLeakySlope = 0.1;
constexpr double kNormEps = 1e-5;  // InstanceNorm1d's and LayerNorm's default
constexpr double kKabschEps = 1e-6;

/// The authors' InstanceNorm1d (no affine, no running statistics) over one cloud's points:
/// x [P, C], each channel to zero mean and unit biased variance.
torch::Tensor InstanceNorm(const torch::Tensor& x) {
    const torch::Tensor mean = x.mean(0, true);
    const torch::Tensor var = (x - mean).pow(2).mean(0, true);
    return (x - mean) / torch::sqrt(var + kNormEps);
}

torch::Tensor Leaky(const torch::Tensor& x) { return torch::leaky_relu(x, kLeakySlope); }

/// Rows of x [S, C] at idx [Q, H]; idx == S reads a zero row (the shadow point).
torch::Tensor GatherShadow(const torch::Tensor& x, const torch::Tensor& idx, double shadow) {
    const torch::Tensor padded = torch::cat({x, torch::full({1, x.size(1)}, shadow, x.options())});
    return padded.index_select(0, idx.reshape(-1)).view({idx.size(0), idx.size(1), x.size(1)});
}

/// The fixed kernel disposition of a freshly built network (see the header), scaled by radius.
torch::Tensor DefaultKernelPoints(double radius) {
    std::vector<double> p = {0, 0, 0};
    for (int axis = 0; axis < 3; ++axis) {
        for (double s : {1.0, -1.0}) {
            std::array<double, 3> v{0, 0, 0};
            v[axis] = s;
            p.insert(p.end(), v.begin(), v.end());
        }
    }
    const double d = 1.0 / std::sqrt(3.0);
    for (double x : {1.0, -1.0}) {
        for (double y : {1.0, -1.0}) {
            for (double z : {1.0, -1.0}) p.insert(p.end(), {x * d, y * d, z * d});
        }
    }
    return (torch::tensor(p, torch::kDouble).view({15, 3}) * (0.66 * radius)).to(torch::kFloat);
}

/// Source overlap labels: 1 where T moves a point of src [N, 3] nearer than r to tgt [M, 3].
torch::Tensor OverlapLabels(const torch::Tensor& src, const torch::Tensor& tgt,
                            const torch::Tensor& T, double r) {
    const torch::Tensor moved =
        torch::matmul(src, T.index({Slice(0, 3), Slice(0, 3)}).t()) + T.index({Slice(0, 3), 3});
    return (std::get<0>(torch::cdist(moved, tgt).min(1)) < r).to(src.scalar_type());
}

torch::Tensor Transform(const torch::Tensor& T, const torch::Tensor& p) {
    return torch::matmul(p, T.index({Slice(0, 3), Slice(0, 3)}).t()) + T.index({Slice(0, 3), 3});
}

/// The authors' InfoNCE (InfoNCELossFull.compute_infonce) of anchor features [P, D] at
/// anchor_xyz against positives [Q, D] at positive_xyz with the symmetrised W.
torch::Tensor InfoNce(const torch::Tensor& W, const torch::Tensor& fa, const torch::Tensor& fp,
                      const torch::Tensor& xa, const torch::Tensor& xp, double r_p, double r_n) {
    const torch::Tensor triu = torch::triu(W);
    const torch::Tensor Ws = triu + triu.t();
    torch::Tensor logits = torch::matmul(torch::matmul(fa, Ws), fp.t());  // [P, Q]
    torch::Tensor idx, mask, ignore;
    {
        torch::NoGradGuard no_grad;
        const torch::Tensor d = torch::cdist(xa, xp);
        auto [d1, i1] = d.min(1, true);
        idx = i1;
        mask = d1.squeeze(1) < r_p;
        ignore = d < r_n;
        ignore.scatter_(1, idx, false);
    }
    logits = logits.masked_fill(ignore, -std::numeric_limits<double>::infinity());
    const torch::Tensor loss = -logits.gather(1, idx).squeeze(1) + torch::logsumexp(logits, 1);
    const torch::Tensor count = mask.sum();
    if (count.item<int64_t>() == 0) return torch::zeros({}, fa.options());
    return loss.masked_select(mask).sum() / count.to(fa.scalar_type());
}

}  // namespace

// Ranges (issue 55: sizes read from a file's tensor shapes were unbounded; d_embed 4096 from
// a 993-byte file allocated 1.9 GB): four times the authors' values (d_embed 256, nhead 8,
// d_feedforward 1024, 6 layers, first_feats_dim 512, neighbour limit 50).
void RegtrConfig::Validate(ParamCheck& c) const {
    InRange(c, "d_embed", d_embed, 6, 1024);
    InRange(c, "nhead", nhead, 1, 32);
    c.Require(d_embed % nhead == 0, "d_embed", "must be a multiple of nhead");
    InRange(c, "d_feedforward", d_feedforward, 1, 4096);
    InRange(c, "num_encoder_layers", num_encoder_layers, 1, 24);
    InRange(c, "first_feats_dim", first_feats_dim, 8, 2048);
    c.Require(first_feats_dim % 8 == 0, "first_feats_dim", "must be a multiple of 8");
    for (const auto& [key, length] :
         {std::pair<const char*, double>{"first_subsampling_dl", first_subsampling_dl},
          {"conv_radius", conv_radius},
          {"kp_extent", kp_extent},
          {"overlap_radius", overlap_radius},
          {"r_p", r_p},
          {"r_n", r_n}}) {
        Positive(c, key, length);
    }
    InRange(c, "neighbor_limit", neighbor_limit, 1, 256);
    c.Require(r_n >= r_p, "r_n", "must be >= r_p");
    NonNegative(c, "wt_overlap", wt_overlap);
    NonNegative(c, "wt_feature", wt_feature);
    NonNegative(c, "wt_corr", wt_corr);
}

nlohmann::json ToJson(const RegtrConfig& c) { return NetConfigJson(c, "regtr"); }

RegtrConfig RegtrConfigFromJson(const nlohmann::json& j) {
    return ParseNetConfig<RegtrConfig>(j, "regtr");
}

torch::Tensor GridSubsample(const torch::Tensor& points, double dl) {
    if (points.dim() != 2 || points.size(1) != 3 || points.size(0) < 1) {
        throw std::invalid_argument("regtr grid subsampling: points must be [N >= 1, 3]");
    }
    const torch::Tensor p = points.detach().to(torch::kCPU, torch::kDouble).contiguous();
    const double* d = p.data_ptr<double>();
    const int64_t n = p.size(0);
    std::map<std::array<int64_t, 3>, std::pair<std::array<double, 3>, int64_t>> voxels;
    for (int64_t i = 0; i < n; ++i) {
        std::array<int64_t, 3> key{};
        for (int c = 0; c < 3; ++c) key[c] = static_cast<int64_t>(std::floor(d[3 * i + c] / dl));
        auto& [sum, count] = voxels[key];
        for (int c = 0; c < 3; ++c) sum[c] += d[3 * i + c];
        ++count;
    }
    torch::Tensor out = torch::empty({static_cast<int64_t>(voxels.size()), 3}, torch::kDouble);
    double* o = out.data_ptr<double>();
    for (const auto& [key, v] : voxels) {
        (void)key;
        for (int c = 0; c < 3; ++c) *o++ = v.first[c] / static_cast<double>(v.second);
    }
    return out.to(points.options());
}

torch::Tensor RadiusNeighbors(const torch::Tensor& queries, const torch::Tensor& supports,
                              double radius, int64_t limit) {
    const torch::Tensor q = queries.detach().to(torch::kCPU, torch::kDouble).contiguous();
    const torch::Tensor s = supports.detach().to(torch::kCPU, torch::kDouble).contiguous();
    const int64_t nq = q.size(0), ns = s.size(0);
    PointCloud cloud(ns, 3);
    std::copy(s.data_ptr<double>(), s.data_ptr<double>() + 3 * ns, cloud.data());
    const KdTree tree(cloud);
    std::vector<std::vector<int64_t>> rows(static_cast<size_t>(nq));
    const double* qd = q.data_ptr<double>();
    std::vector<std::pair<Eigen::Index, double>> found;
    const double r2 = radius * radius;
    int64_t widest = 0;
    for (int64_t i = 0; i < nq; ++i) {
        found.clear();
        tree.Radius(Eigen::Vector3d(qd[3 * i], qd[3 * i + 1], qd[3 * i + 2]), radius, found);
        auto& keep = rows[static_cast<size_t>(i)];
        for (const auto& [j, sq] : found) {
            if (sq < r2) keep.push_back(j);
        }
        std::sort(keep.begin(), keep.end());
        if (static_cast<int64_t>(keep.size()) > limit) keep.resize(static_cast<size_t>(limit));
        widest = std::max<int64_t>(widest, static_cast<int64_t>(keep.size()));
    }
    // Columns that are shadow in every row contribute nothing (zero influence, zero features,
    // not counted): drop them, keeping one whenever a row is not full, so a max-pool over a
    // row that is not full still sees the shadow's zero as the authors' 50 columns do.
    const int64_t width = std::min(limit, widest + 1);
    torch::Tensor out = torch::full({nq, width}, ns, torch::kLong);
    int64_t* o = out.data_ptr<int64_t>();
    for (int64_t i = 0; i < nq; ++i) {
        const auto& keep = rows[static_cast<size_t>(i)];
        std::copy(keep.begin(), keep.end(), o + i * width);
    }
    return out.to(queries.device());
}

// ---- KPConv encoder ---------------------------------------------------------------------------

RegtrKpconvImpl::RegtrKpconvImpl(int64_t in, int64_t out, double radius, double extent_)
    : extent(extent_) {
    weights = register_parameter("weights", torch::empty({15, in, out}));
    // The authors' kaiming_uniform_(a = sqrt 5) on a [K, in, out] tensor: fan_in = in * out.
    nn::init::kaiming_uniform_(weights, std::sqrt(5.0));
    // A Parameter with requires_grad False in the authors' module; a buffer here (same key).
    kernel_points = register_buffer("kernel_points", DefaultKernelPoints(radius));
}

torch::Tensor RegtrKpconvImpl::forward(const torch::Tensor& q, const torch::Tensor& s,
                                       const torch::Tensor& nb, const torch::Tensor& x) {
    const int64_t Q = q.size(0), H = nb.size(1), K = weights.size(0), C = x.size(1);
    if (!torch::GradMode::is_enabled() && q.device().is_cpu()) {
        // The fused loop (kernels.hpp): the same sums, no [Q, H, K, 3] or [Q, H, C] temporaries
        // and one pass instead of Q small batched products.
        const torch::Tensor qc = q.contiguous(), sc = s.contiguous(), xc = x.contiguous();
        const torch::Tensor nbc = nb.to(torch::kLong).contiguous();
        const torch::Tensor kp = kernel_points.to(q.dtype()).contiguous();
        // The authors count the neighbours whose features sum to more than 0.
        const torch::Tensor positive = (xc.sum(1) > 0).contiguous();
        torch::Tensor sums = torch::empty({Q, K, C}, x.options());
        torch::Tensor count = torch::empty({Q}, x.options());
        AT_DISPATCH_FLOATING_TYPES(x.scalar_type(), "regtr_kpconv", [&] {
            KpconvNeighbourSums(qc.data_ptr<scalar_t>(), Q, sc.data_ptr<scalar_t>(), s.size(0),
                                nbc.data_ptr<int64_t>(), H, kp.data_ptr<scalar_t>(), K, extent,
                                xc.data_ptr<scalar_t>(), C, positive.data_ptr<bool>(),
                                sums.data_ptr<scalar_t>(), count.data_ptr<scalar_t>());
        });
        return torch::matmul(sums.view({Q, K * C}), weights.reshape({K * C, weights.size(2)}))
            .div_(count.unsqueeze(1));
    }
    // Neighbour offsets [Q, H, 3]; the shadow point sits at 1e6 (weight 0).
    const torch::Tensor nbr = GatherShadow(s, nb, 1e6) - q.unsqueeze(1);
    const torch::Tensor diff = nbr.unsqueeze(2) - kernel_points.to(q.dtype());  // [Q, H, K, 3]
    const torch::Tensor sq = diff.pow(2).sum(3);
    const torch::Tensor w = torch::clamp_min(1.0 - torch::sqrt(sq) / extent, 0.0).transpose(1, 2);
    const torch::Tensor nx = GatherShadow(x, nb, 0.0);  // [Q, H, C]
    const torch::Tensor weighted = torch::bmm(w, nx);   // [Q, K, C]
    torch::Tensor out =
        torch::matmul(weighted.reshape({Q, K * C}), weights.reshape({K * C, weights.size(2)}));
    // The authors divide by the neighbours whose features sum to more than 0 (at least 1).
    const torch::Tensor count = torch::clamp_min((nx.sum(2) > 0).sum(1), 1).to(out.dtype());
    (void)H;
    return out / count.unsqueeze(1);
}

RegtrUnaryImpl::RegtrUnaryImpl(int64_t in, int64_t out, bool relu_) : relu(relu_) {
    mlp = register_module("mlp", nn::Linear(nn::LinearOptions(in, out).bias(false)));
}

torch::Tensor RegtrUnaryImpl::forward(const torch::Tensor& x) {
    const torch::Tensor y = InstanceNorm(mlp->forward(x));
    return relu ? Leaky(y) : y;
}

RegtrBlockImpl::RegtrBlockImpl(bool simple_, bool strided_, int64_t in, int64_t out, double radius,
                               double extent)
    : simple(simple_), strided(strided_) {
    if (simple) {
        kpconv = register_module("KPConv", RegtrKpconv(in, out / 2, radius, extent));
        return;
    }
    if (in != out / 4) unary1 = register_module("unary1", RegtrUnary(in, out / 4, true));
    kpconv = register_module("KPConv", RegtrKpconv(out / 4, out / 4, radius, extent));
    unary2 = register_module("unary2", RegtrUnary(out / 4, out, false));
    if (in != out) shortcut = register_module("unary_shortcut", RegtrUnary(in, out, false));
}

torch::Tensor RegtrBlockImpl::forward(const torch::Tensor& x, const torch::Tensor& q,
                                      const torch::Tensor& s, const torch::Tensor& nb) {
    if (simple) return Leaky(InstanceNorm(kpconv->forward(q, s, nb, x)));
    torch::Tensor h = unary1 ? unary1->forward(x) : x;
    h = Leaky(InstanceNorm(kpconv->forward(q, s, nb, h)));
    h = unary2->forward(h);
    torch::Tensor sc = x;
    if (strided) sc = std::get<0>(GatherShadow(x, nb, 0.0).max(1));
    if (shortcut) sc = shortcut->forward(sc);
    return Leaky(h + sc);
}

// ---- transformer ----------------------------------------------------------------------------

RegtrAttentionImpl::RegtrAttentionImpl(int64_t d, int64_t heads_) : heads(heads_) {
    in_proj_weight = register_parameter("in_proj_weight", torch::empty({3 * d, d}));
    nn::init::xavier_uniform_(in_proj_weight);
    in_proj_bias = register_parameter("in_proj_bias", torch::zeros({3 * d}));
    out_proj = register_module("out_proj", nn::Linear(d, d));
    torch::NoGradGuard no_grad;
    out_proj->bias.zero_();
}

torch::Tensor RegtrAttentionImpl::forward(const torch::Tensor& query, const torch::Tensor& key,
                                          const torch::Tensor& value) {
    const int64_t d = query.size(1), hd = d / heads, L = query.size(0), S = key.size(0);
    const auto proj = [&](const torch::Tensor& x, int64_t i) {
        return F::linear(x, in_proj_weight.narrow(0, i * d, d), in_proj_bias.narrow(0, i * d, d));
    };
    if (!torch::GradMode::is_enabled() && query.device().is_cpu()) {
        // One pass a query row (networks/layers/attention_rows.hpp), the same products.
        const torch::Tensor q = proj(query, 0).div_(std::sqrt(static_cast<double>(hd)));
        const torch::Tensor k = proj(key, 1).contiguous(), v = proj(value, 2).contiguous();
        torch::Tensor o = torch::empty({L, d}, q.options());
        AT_DISPATCH_FLOATING_TYPES(q.scalar_type(), "regtr_attention", [&] {
            AttentionRows(q.data_ptr<scalar_t>(), k.data_ptr<scalar_t>(), v.data_ptr<scalar_t>(), L,
                          S, heads, d, o.data_ptr<scalar_t>());
        });
        return out_proj->forward(o);
    }
    const torch::Tensor q =
        (proj(query, 0) / std::sqrt(static_cast<double>(hd))).view({L, heads, hd}).transpose(0, 1);
    const torch::Tensor k = proj(key, 1).view({S, heads, hd}).transpose(0, 1);
    const torch::Tensor v = proj(value, 2).view({S, heads, hd}).transpose(0, 1);
    const torch::Tensor a = torch::softmax(torch::bmm(q, k.transpose(1, 2)), -1);
    return out_proj->forward(torch::bmm(a, v).transpose(0, 1).reshape({L, d}));
}

RegtrCrossLayerImpl::RegtrCrossLayerImpl(int64_t d, int64_t heads, int64_t ff) {
    self_attn = register_module("self_attn", RegtrAttention(d, heads));
    multihead_attn = register_module("multihead_attn", RegtrAttention(d, heads));
    linear1 = register_module("linear1", nn::Linear(d, ff));
    linear2 = register_module("linear2", nn::Linear(ff, d));
    const auto ln = [&] { return nn::LayerNorm(nn::LayerNormOptions({d})); };
    norm1 = register_module("norm1", ln());
    norm2 = register_module("norm2", ln());
    norm3 = register_module("norm3", ln());
}

std::pair<torch::Tensor, torch::Tensor> RegtrCrossLayerImpl::forward(torch::Tensor src,
                                                                     torch::Tensor tgt,
                                                                     const torch::Tensor& sp,
                                                                     const torch::Tensor& tp) {
    // Self attention; queries, keys and values all carry the position encoding.
    torch::Tensor s2 = norm1->forward(src) + sp;
    src = src + self_attn->forward(s2, s2, s2);
    torch::Tensor t2 = norm1->forward(tgt) + tp;
    tgt = tgt + self_attn->forward(t2, t2, t2);
    // Cross attention, both from the same normalised inputs.
    s2 = norm2->forward(src) + sp;
    t2 = norm2->forward(tgt) + tp;
    const torch::Tensor s3 = multihead_attn->forward(s2, t2, t2);
    const torch::Tensor t3 = multihead_attn->forward(t2, s2, s2);
    src = src + s3;
    tgt = tgt + t3;
    src = src + linear2->forward(torch::relu(linear1->forward(norm3->forward(src))));
    tgt = tgt + linear2->forward(torch::relu(linear1->forward(norm3->forward(tgt))));
    return {src, tgt};
}

torch::Tensor RegtrPositionEncoding(const torch::Tensor& xyz, int64_t d) {
    const int64_t f = d / 3 / 2 * 2, pad = d - 3 * f;
    // dim_t computed in float32 like the authors' (torch.arange float32).
    const torch::Tensor i = torch::arange(f, torch::kFloat);
    const torch::Tensor dim_t =
        torch::pow(10000.0, 2 * torch::div(i, 2, "trunc") / static_cast<double>(f)).to(xyz.dtype());
    const torch::Tensor div = (xyz * (2 * M_PI)).unsqueeze(-1) / dim_t;  // [P, 3, f]
    const torch::Tensor pe =
        torch::stack({div.index({Slice(), Slice(), Slice(0, torch::indexing::None, 2)}).sin(),
                      div.index({Slice(), Slice(), Slice(1, torch::indexing::None, 2)}).cos()},
                     -1)
            .reshape({xyz.size(0), 3 * f});
    return F::pad(pe, F::PadFuncOptions({0, pad}));
}

torch::Tensor WeightedKabsch(const torch::Tensor& a, const torch::Tensor& b,
                             const torch::Tensor& w) {
    const torch::Tensor wn = (w / torch::clamp_min(w.sum(), kKabschEps)).unsqueeze(1);
    const torch::Tensor ca = (a * wn).sum(0), cb = (b * wn).sum(0);
    const torch::Tensor cov = torch::matmul((a - ca).t(), (b - cb) * wn);
    const auto [U, S, Vh] = torch::linalg_svd(cov, true);
    (void)S;
    const torch::Tensor V = Vh.t();
    torch::Tensor R = torch::matmul(V, U.t());
    if (torch::det(R).item<double>() <= 0) {
        torch::Tensor Vn = V.clone();
        Vn.index_put_({Slice(), 2}, -V.index({Slice(), 2}));
        R = torch::matmul(Vn, U.t());
    }
    torch::Tensor T = torch::eye(4, a.options());
    T.index_put_({Slice(0, 3), Slice(0, 3)}, R);
    T.index_put_({Slice(0, 3), 3}, cb - torch::matmul(R, ca));
    return T;
}

// ---- the network ----------------------------------------------------------------------------

RegtrNet::RegtrNet(const RegtrConfig& config) : config_(config) {
    const int64_t F0 = config.first_feats_dim;
    const double r0 = config.first_subsampling_dl * config.conv_radius;
    const double e0 = config.first_subsampling_dl * config.kp_extent;
    auto encoder = register_module("kpf_encoder", std::make_shared<nn::Module>());
    blocks_ = encoder->register_module("encoder_blocks", nn::ModuleList());
    // simple, resnetb, resnetb, resnetb_strided | resnetb, resnetb (the ModelNet architecture).
    blocks_->push_back(RegtrBlock(true, false, 1, F0, r0, e0));
    blocks_->push_back(RegtrBlock(false, false, F0 / 2, F0, r0, e0));
    blocks_->push_back(RegtrBlock(false, false, F0, F0, r0, e0));
    blocks_->push_back(RegtrBlock(false, true, F0, F0, r0, e0));
    blocks_->push_back(RegtrBlock(false, false, F0, 2 * F0, 2 * r0, 2 * e0));
    blocks_->push_back(RegtrBlock(false, false, 2 * F0, 2 * F0, 2 * r0, 2 * e0));
    feat_proj_ = register_module("feat_proj", nn::Linear(2 * F0, config.d_embed));
    auto transformer = register_module("transformer_encoder", std::make_shared<nn::Module>());
    layers_ = transformer->register_module("layers", nn::ModuleList());
    for (int i = 0; i < config.num_encoder_layers; ++i) {
        layers_->push_back(RegtrCrossLayer(config.d_embed, config.nhead, config.d_feedforward));
    }
    final_norm_ =
        transformer->register_module("norm", nn::LayerNorm(nn::LayerNormOptions({config.d_embed})));
    auto decoder = register_module("correspondence_decoder", std::make_shared<nn::Module>());
    const int64_t d = config.d_embed;
    coor_mlp_ = decoder->register_module(
        "coor_mlp", nn::Sequential(nn::Linear(d, d), nn::ReLU(), nn::Linear(d, d), nn::ReLU(),
                                   nn::Linear(d, 3)));
    conf_logits_ = decoder->register_module("conf_logits_decoder", nn::Linear(d, 1));
    auto fc = register_module("feature_criterion", std::make_shared<nn::Module>());
    feature_W_ = fc->register_parameter("W", torch::randn({d, d}) * 0.1);
    auto fcu = register_module("feature_criterion_un", std::make_shared<nn::Module>());
    feature_un_W_ = fcu->register_parameter("W", torch::randn({d, d}) * 0.1);
}

std::tuple<torch::Tensor, torch::Tensor, torch::Tensor> RegtrNet::Encode(const torch::Tensor& p0) {
    const double r0 = config_.first_subsampling_dl * config_.conv_radius;
    const int64_t lim = config_.neighbor_limit;
    const torch::Tensor p1 = GridSubsample(p0, 2 * config_.first_subsampling_dl);
    const torch::Tensor nb0 = RadiusNeighbors(p0, p0, r0, lim);
    const torch::Tensor pool = RadiusNeighbors(p1, p0, r0, lim);
    const torch::Tensor nb1 = RadiusNeighbors(p1, p1, 2 * r0, lim);
    torch::Tensor x = torch::ones({p0.size(0), 1}, p0.options());
    const auto block = [&](int i) { return blocks_->ptr<RegtrBlockImpl>(i); };
    x = block(0)->forward(x, p0, p0, nb0);
    x = block(1)->forward(x, p0, p0, nb0);
    x = block(2)->forward(x, p0, p0, nb0);
    x = block(3)->forward(x, p1, p0, pool);
    x = block(4)->forward(x, p1, p1, nb1);
    x = block(5)->forward(x, p1, p1, nb1);
    return {p1, pool, feat_proj_->forward(x)};
}

NetOutput RegtrNet::Forward(const PairBatch& batch) {
    const torch::Tensor& src = batch.source;
    const torch::Tensor& tgt = batch.target;
    if (src.dim() != 3 || tgt.dim() != 3 || src.size(2) != 3 || tgt.size(2) != 3 ||
        src.size(0) != tgt.size(0) || src.size(1) < 1 || tgt.size(1) < 1) {
        throw std::invalid_argument("regtr: clouds must be [B, N, 3] and [B, M, 3], N, M >= 1");
    }
    const auto dtype = feat_proj_->weight.scalar_type();
    NetOutput out;
    std::vector<torch::Tensor> Ts;
    for (int64_t b = 0; b < src.size(0); ++b) {
        const torch::Tensor ps = src[b].to(dtype), pt = tgt[b].to(dtype);
        auto [kp_s, pool_s, fs] = Encode(ps);
        auto [kp_t, pool_t, ft] = Encode(pt);
        const torch::Tensor pe_s = RegtrPositionEncoding(kp_s, config_.d_embed);
        const torch::Tensor pe_t = RegtrPositionEncoding(kp_t, config_.d_embed);
        for (size_t i = 0; i < layers_->size(); ++i) {
            std::tie(fs, ft) = layers_->ptr<RegtrCrossLayerImpl>(i)->forward(fs, ft, pe_s, pe_t);
        }
        fs = final_norm_->forward(fs);
        ft = final_norm_->forward(ft);
        const torch::Tensor corr_s = coor_mlp_->forward(fs), corr_t = coor_mlp_->forward(ft);
        const torch::Tensor ov_s = conf_logits_->forward(fs).squeeze(1);
        const torch::Tensor ov_t = conf_logits_->forward(ft).squeeze(1);
        {
            torch::NoGradGuard no_grad;
            const torch::Tensor a = torch::cat({kp_s, corr_t}).to(torch::kDouble);
            const torch::Tensor c = torch::cat({corr_s, kp_t}).to(torch::kDouble);
            const torch::Tensor w = torch::cat({ov_s.sigmoid(), ov_t.sigmoid()}).to(torch::kDouble);
            Ts.push_back(WeightedKabsch(a, c, w).to(src.dtype()));
        }
        const std::string n = "_" + std::to_string(b);
        out.aux["src_kp" + n] = kp_s;
        out.aux["tgt_kp" + n] = kp_t;
        out.aux["src_pool" + n] = pool_s;
        out.aux["tgt_pool" + n] = pool_t;
        out.aux["src_corr" + n] = corr_s;
        out.aux["tgt_corr" + n] = corr_t;
        out.aux["src_overlap" + n] = ov_s;
        out.aux["tgt_overlap" + n] = ov_t;
        out.aux["src_feat" + n] = fs;
        out.aux["tgt_feat" + n] = ft;
    }
    out.T = torch::stack(Ts);
    return out;
}

LossTerms RegtrNet::Loss(const PairBatch& batch, const NetOutput& output) {
    if (!batch.T_gt.defined()) throw std::invalid_argument("regtr loss: the batch has no T_gt");
    const auto dtype = feat_proj_->weight.scalar_type();
    std::vector<torch::Tensor> logits, labels, err_s, w_s, err_t, w_t, feat;
    for (int64_t b = 0; b < batch.source.size(0); ++b) {
        const std::string n = "_" + std::to_string(b);
        const torch::Tensor T = batch.T_gt[b].to(dtype);
        const torch::Tensor Tinv = torch::inverse(T);
        const torch::Tensor ps = batch.source[b].to(dtype), pt = batch.target[b].to(dtype);
        // Ground-truth overlap of the input points (the batch's labels, else computed with
        // overlap_radius), average-pooled onto the superpoints through the pooling neighbours.
        const torch::Tensor os = batch.source_overlap.defined()
                                     ? batch.source_overlap[b].to(dtype)
                                     : OverlapLabels(ps, pt, T, config_.overlap_radius);
        const torch::Tensor ot = batch.target_overlap.defined()
                                     ? batch.target_overlap[b].to(dtype)
                                     : OverlapLabels(pt, ps, Tinv, config_.overlap_radius);
        const auto pooled = [&](const torch::Tensor& o, const torch::Tensor& pool) {
            const torch::Tensor valid = (pool < o.size(0)).to(dtype);
            const torch::Tensor g = GatherShadow(o.unsqueeze(1), pool, 0.0).squeeze(2) * valid;
            return torch::clamp(g.sum(1) / valid.sum(1), 0.0, 1.0);
        };
        const torch::Tensor gs = pooled(os, output.aux.at("src_pool" + n));
        const torch::Tensor gt = pooled(ot, output.aux.at("tgt_pool" + n));
        logits.push_back(output.aux.at("src_overlap" + n));
        logits.push_back(output.aux.at("tgt_overlap" + n));
        labels.push_back(gs);
        labels.push_back(gt);
        const torch::Tensor& kp_s = output.aux.at("src_kp" + n);
        const torch::Tensor& kp_t = output.aux.at("tgt_kp" + n);
        err_s.push_back((output.aux.at("src_corr" + n) - Transform(T, kp_s)).abs().sum(1));
        w_s.push_back(gs);
        err_t.push_back((output.aux.at("tgt_corr" + n) - Transform(Tinv, kp_t)).abs().sum(1));
        w_t.push_back(gt);
        feat.push_back(InfoNce(feature_W_, output.aux.at("src_feat" + n),
                               output.aux.at("tgt_feat" + n), Transform(T, kp_s), kp_t, config_.r_p,
                               config_.r_n));
    }
    const auto weighted = [](const std::vector<torch::Tensor>& e,
                             const std::vector<torch::Tensor>& w) {
        const torch::Tensor ww = torch::cat(w);
        return (ww * torch::cat(e)).sum() / torch::clamp_min(ww.sum(), kKabschEps);
    };
    LossTerms terms;
    terms["overlap"] = config_.wt_overlap *
                       F::binary_cross_entropy_with_logits(torch::cat(logits), torch::cat(labels));
    terms["feature"] = config_.wt_feature * torch::stack(feat).mean();
    terms["corr"] = config_.wt_corr * (weighted(err_s, w_s) + weighted(err_t, w_t));
    terms["total"] = terms["overlap"] + terms["feature"] + terms["corr"];
    return terms;
}

std::map<std::string, int64_t> RegtrForwardMacs(const RegtrConfig& c, int64_t n, int64_t m) {
    const int64_t F0 = c.first_feats_dim, H = c.neighbor_limit, K = 15, d = c.d_embed;
    const auto super = [](int64_t p) { return std::max<int64_t>(1, std::min(p, p * 700 / 717)); };
    std::map<std::string, int64_t> parts{
        {"kpconv", 0}, {"unary", 0}, {"attention", 0}, {"feedforward", 0}, {"heads", 0}};
    // KPConv on Q queries, C -> O: the influence-weighted sums (K H C) and the kernel (K C O).
    const auto kp = [&](int64_t q, int64_t ci, int64_t co) {
        return q * (K * H * ci + K * ci * co);
    };
    for (const int64_t p : {n, m}) {
        const int64_t v = super(p);
        parts["kpconv"] += kp(p, 1, F0 / 2) + 2 * kp(p, F0 / 4, F0 / 4) + kp(v, F0 / 4, F0 / 4) +
                           2 * kp(v, F0 / 2, F0 / 2);
        parts["unary"] += p * (F0 / 2 * F0 / 4 + F0 / 4 * F0 + F0 / 2 * F0) +
                          p * (F0 * F0 / 4 + F0 / 4 * F0) + p * F0 * F0 / 4 + v * F0 / 4 * F0 +
                          v * (F0 * F0 / 2 + F0 / 2 * 2 * F0 + F0 * 2 * F0) +
                          v * (2 * F0 * F0 / 2 + F0 / 2 * 2 * F0) + v * 2 * F0 * d;
        parts["heads"] += v * (2 * d * d + 3 * d + d);
    }
    const int64_t vs = super(n), vt = super(m), L = c.num_encoder_layers;
    // Per layer: self attention of each cloud, cross attention both ways (4 d^2 per query
    // point for the projections when it also projects the other cloud's keys and values).
    const int64_t self = 4 * d * d * (vs + vt) + 2 * d * (vs * vs + vt * vt);
    const int64_t cross = 4 * d * d * (vs + vt) + 4 * d * vs * vt;
    parts["attention"] = L * (self + cross);
    parts["feedforward"] = L * 2 * d * c.d_feedforward * (vs + vt);
    return parts;
}

}  // namespace regbench::networks
