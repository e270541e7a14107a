#include "networks/families/omnet/net.hpp"

#include <Eigen/Geometry>
#include <limits>
#include <stdexcept>

#include "networks/family_config.hpp"
#include "networks/layers/layers.hpp"

namespace regbench::networks {

namespace {

namespace nn = torch::nn;
namespace F = torch::nn::functional;
using torch::indexing::Slice;

/// The authors' class weights of the overlap cross-entropy: not overlapping, overlapping.
constexpr double kNotOverlapWeight = 0.7;
constexpr double kOverlapWeight = 0.3;

/// Conv1d (1x1, with bias), BatchNorm1d, ReLU: the authors' conv_block.
nn::Sequential ConvBlock(int64_t in, int64_t out) {
    return nn::Sequential(nn::Conv1d(nn::Conv1dOptions(in, out, 1)), nn::BatchNorm1d(out),
                          nn::ReLU());
}

/// Linear, BatchNorm1d, ReLU: the authors' fc_block.
nn::Sequential FcBlock(int64_t in, int64_t out) {
    return nn::Sequential(nn::Linear(in, out), nn::BatchNorm1d(out), nn::ReLU());
}

/// W x + b for a weight [out, in], points [B, in, N] and a bias [out]: one GEMM (the bias
/// broadcast into it) per cloud. LibTorch's Conv1d takes a slower path for 1x1 kernels.
torch::Tensor Affine(const torch::Tensor& W, const torch::Tensor& b, const torch::Tensor& x) {
    if (x.size(0) == 1) return torch::addmm(b.view({-1, 1}), W, x[0]).unsqueeze(0);
    return torch::matmul(W, x) + b.view({-1, 1});
}

/// An eval-mode BatchNorm as y = scale x + shift (per channel).
std::pair<torch::Tensor, torch::Tensor> FoldedBatchNorm(const nn::BatchNorm1dImpl& bn) {
    const torch::Tensor scale = bn.weight / torch::sqrt(bn.running_var + bn.options.eps());
    return {scale, bn.bias - bn.running_mean * scale};
}

/// A conv_block (Conv1d, BN, ReLU) or a bare Conv1d block on points [B, in, N]. In eval mode
/// the BatchNorm is folded into the convolution (its running statistics are constants): one
/// GEMM and one ReLU pass instead of GEMM, bias, normalisation and ReLU passes.
torch::Tensor Pointwise(const nn::Sequential& block, const torch::Tensor& x) {
    const auto conv = std::dynamic_pointer_cast<nn::Conv1dImpl>(block->ptr(0));
    const torch::Tensor W = conv->weight.squeeze(2);
    if (block->size() == 1) return Affine(W, conv->bias, x);
    const auto bn = std::dynamic_pointer_cast<nn::BatchNorm1dImpl>(block->ptr(1));
    if (bn->is_training()) return bn->forward(Affine(W, conv->bias, x)).relu();
    const auto [scale, shift] = FoldedBatchNorm(*bn);
    return Affine(W * scale.unsqueeze(1), conv->bias * scale + shift, x).relu_();
}

/// Registers `blocks` on `m` as <prefix>1, <prefix>2, ... and returns their handles.
std::vector<nn::Sequential> RegisterBlocks(nn::Module& m, const std::string& prefix,
                                           std::vector<nn::Sequential> blocks) {
    for (size_t i = 0; i < blocks.size(); ++i) {
        blocks[i] = m.register_module(prefix + std::to_string(i + 1), blocks[i]);
    }
    return blocks;
}

/// Quaternion (w, x, y, z) of a rotation with w >= 0 (Eigen's conversion), as [4] float64.
std::vector<double> QuaternionOf(const torch::Tensor& R) {
    const torch::Tensor r = R.to(torch::kDouble).contiguous();
    Eigen::Matrix3d m;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) m(i, j) = r[i][j].item<double>();
    }
    Eigen::Quaterniond q(m);
    if (q.w() < 0) q.coeffs() *= -1.0;
    return {q.w(), q.x(), q.y(), q.z()};
}

/// 0/1 overlap labels [B, P] of the points `a` [B, P, 3] (already moved by T_gt) against `b`
/// [B, Q, 3]: held by `mask_a` [B, P] and nearer than `dist` to a point `mask_b` holds.
torch::Tensor OverlapLabels(const torch::Tensor& a, const torch::Tensor& b,
                            const torch::Tensor& mask_a, const torch::Tensor& mask_b, double dist) {
    const torch::Tensor d = torch::cdist(a, b);
    const torch::Tensor inf = torch::full({}, std::numeric_limits<double>::infinity(), d.options());
    const torch::Tensor nearest = torch::where(mask_b.unsqueeze(1) > 0, d, inf).amin(2);
    return torch::logical_and(nearest<dist, mask_a> 0).to(torch::kLong);
}

}  // namespace

// Ranges: the authors run 4 iterations, a mask delay of 2 and their full widths (divisor 1).
// Each iteration has its own weights, so iterations were unbounded memory (issue 55): 8 times
// the authors' 4.
void OmnetConfig::Validate(ParamCheck& c) const {
    InRange(c, "iterations", iterations, 1, 32);
    InRange(c, "width_divisor", width_divisor, 1, 64);
    c.Require(width_divisor >= 1 && 64 % width_divisor == 0, "width_divisor",
              "must divide 64 (1, 2, 4, ..., 64), got " + std::to_string(width_divisor));
    InRange(c, "mask_delay", mask_delay, 0, 32);
    Positive(c, "overlap_dist", overlap_dist);
    NonNegative(c, "quat_weight", quat_weight);
    NonNegative(c, "trans_weight", trans_weight);
}

nlohmann::json ToJson(const OmnetConfig& c) { return NetConfigJson(c, "omnet"); }

OmnetConfig OmnetConfigFromJson(const nlohmann::json& j) {
    return ParseNetConfig<OmnetConfig>(j, "omnet");
}

OmnetWidths::OmnetWidths(int divisor)
    : w64(64 / divisor),
      w128(128 / divisor),
      w256(256 / divisor),
      w512(512 / divisor),
      w1024(1024 / divisor),
      w2048(2048 / divisor) {}

OmnetEncoderImpl::OmnetEncoderImpl(const OmnetWidths& w)
    : blocks_(RegisterBlocks(*this, "conv_block",
                             {ConvBlock(3, w.w64), ConvBlock(w.w64, w.w64), ConvBlock(w.w64, w.w64),
                              ConvBlock(w.w64, w.w128), ConvBlock(w.w128, w.w1024)})) {}

std::pair<torch::Tensor, torch::Tensor> OmnetEncoderImpl::forward(const torch::Tensor& x,
                                                                  const torch::Tensor& mask) {
    const torch::Tensor f64 = Pointwise(blocks_[1], Pointwise(blocks_[0], x));
    const torch::Tensor f1024 =
        Pointwise(blocks_[4], Pointwise(blocks_[3], Pointwise(blocks_[2], f64)));
    return {f64 * mask, std::get<0>((f1024 * mask).max(2, true))};
}

OmnetFusionImpl::OmnetFusionImpl(const OmnetWidths& w)
    : local_width_(w.w64),
      blocks_(RegisterBlocks(*this, "conv_block",
                             {ConvBlock(w.w64 + 2 * w.w1024, w.w1024), ConvBlock(w.w1024, w.w1024),
                              ConvBlock(w.w1024, w.w512)})) {}

torch::Tensor OmnetFusionImpl::forward(const torch::Tensor& local, const torch::Tensor& own_global,
                                       const torch::Tensor& other_global,
                                       const torch::Tensor& mask) {
    // The first convolution of [local; own global; other global] (the authors' order), split:
    // the global part is the same for every point, so it is computed once and broadcast.
    const auto conv = std::dynamic_pointer_cast<nn::Conv1dImpl>(blocks_[0]->ptr(0));
    const torch::Tensor W = conv->weight.squeeze(2);  // [out, 64 + 2 x 1024]
    const int64_t g = own_global.size(1);
    torch::Tensor per_cloud =
        torch::matmul(W.index({Slice(), Slice(local_width_, local_width_ + g)}), own_global) +
        torch::matmul(W.index({Slice(), Slice(local_width_ + g, torch::indexing::None)}),
                      other_global) +
        conv->bias.view({1, -1, 1});  // [B, out, 1]
    torch::Tensor W_local = W.index({Slice(), Slice(0, local_width_)});
    const auto bn = std::dynamic_pointer_cast<nn::BatchNorm1dImpl>(blocks_[0]->ptr(1));
    const bool folded = !bn->is_training();
    if (folded) {  // as Pointwise: the eval-mode BatchNorm folded into the convolution
        const auto [scale, shift] = FoldedBatchNorm(*bn);
        W_local = W_local * scale.unsqueeze(1);
        per_cloud = per_cloud * scale.view({1, -1, 1}) + shift.view({1, -1, 1});
    }
    const torch::Tensor pre = local.size(0) == 1
                                  ? torch::addmm(per_cloud[0], W_local, local[0]).unsqueeze(0)
                                  : torch::matmul(W_local, local) + per_cloud;
    torch::Tensor h = folded ? pre.relu_() : bn->forward(pre).relu();
    h = Pointwise(blocks_[2], Pointwise(blocks_[1], h));
    return h * mask;
}

OmnetDecoderImpl::OmnetDecoderImpl(const OmnetWidths& w)
    : blocks_(RegisterBlocks(
          *this, "conv_block",
          {ConvBlock(w.w512, w.w512), ConvBlock(w.w512, w.w256), ConvBlock(w.w256, w.w256),
           nn::Sequential(nn::Conv1d(nn::Conv1dOptions(w.w256, 2, 1)))})) {}

std::pair<torch::Tensor, torch::Tensor> OmnetDecoderImpl::forward(const torch::Tensor& fused) {
    const torch::Tensor a = Pointwise(blocks_[0], fused);
    const torch::Tensor b = Pointwise(blocks_[1], a);
    const torch::Tensor c = Pointwise(blocks_[2], b);
    return {torch::cat({a, b, c}, 1), Pointwise(blocks_[3], c)};
}

OmnetRegressionImpl::OmnetRegressionImpl(const OmnetWidths& w) {
    blocks_ = RegisterBlocks(*this, "fc_block",
                             {FcBlock(2 * (w.w512 + w.w1024), w.w2048), FcBlock(w.w2048, w.w1024),
                              FcBlock(w.w1024, w.w512), FcBlock(w.w512, w.w256)});
    blocks_.push_back(register_module("final_fc", nn::Sequential(nn::Linear(w.w256, 7))));
}

torch::Tensor OmnetRegressionImpl::forward(const torch::Tensor& x) {
    torch::Tensor h = x;
    for (auto& b : blocks_) h = b->forward(h);
    const torch::Tensor quat =
        F::normalize(h.index({Slice(), Slice(0, 4)}), F::NormalizeFuncOptions().dim(1).eps(1e-12));
    return torch::cat({quat, h.index({Slice(), Slice(4, 7)})}, 1);
}

torch::Tensor QuaternionToMatrix(const torch::Tensor& q) {
    const torch::Tensor w = q.select(1, 0), x = q.select(1, 1), y = q.select(1, 2),
                        z = q.select(1, 3);
    const auto row = [](const torch::Tensor& a, const torch::Tensor& b, const torch::Tensor& c) {
        return torch::stack({a, b, c}, 1);
    };
    return torch::stack(
        {row(w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)),
         row(2 * (x * y + w * z), w * w + y * y - x * x - z * z, 2 * (y * z - w * x)),
         row(2 * (x * z - w * y), 2 * (y * z + w * x), w * w + z * z - x * x - y * y)},
        1);
}

torch::Tensor ComposePoses(const torch::Tensor& first, const torch::Tensor& then) {
    const torch::Tensor a = first.index({Slice(), Slice(0, 4)});
    const torch::Tensor b = then.index({Slice(), Slice(0, 4)});
    const auto c = [](const torch::Tensor& q, int i) { return q.select(1, i); };
    // Hamilton product b * a: rotate by a first, then by b.
    const torch::Tensor q = torch::stack(
        {c(b, 0) * c(a, 0) - c(b, 1) * c(a, 1) - c(b, 2) * c(a, 2) - c(b, 3) * c(a, 3),
         c(b, 0) * c(a, 1) + c(b, 1) * c(a, 0) + c(b, 2) * c(a, 3) - c(b, 3) * c(a, 2),
         c(b, 0) * c(a, 2) - c(b, 1) * c(a, 3) + c(b, 2) * c(a, 0) + c(b, 3) * c(a, 1),
         c(b, 0) * c(a, 3) + c(b, 1) * c(a, 2) - c(b, 2) * c(a, 1) + c(b, 3) * c(a, 0)},
        1);
    const torch::Tensor t =
        torch::bmm(QuaternionToMatrix(b), first.index({Slice(), Slice(4, 7)}).unsqueeze(2))
            .squeeze(2) +
        then.index({Slice(), Slice(4, 7)});
    return torch::cat({q, t}, 1);
}

OmnetNet::OmnetNet(const OmnetConfig& config) : config_(config) {
    const OmnetWidths w(config.width_divisor);
    encoder_ = register_module("encoder", nn::ModuleList());
    fusion_ = register_module("fusion", nn::ModuleList());
    decoder_ = register_module("decoder", nn::ModuleList());
    regression_ = register_module("regression", nn::ModuleList());
    for (int i = 0; i < config.iterations; ++i) {
        encoder_->push_back(OmnetEncoder(w));
        fusion_->push_back(OmnetFusion(w));
        decoder_->push_back(OmnetDecoder(w));
        regression_->push_back(OmnetRegression(w));
    }
}

NetOutput OmnetNet::Forward(const PairBatch& batch) {
    const torch::Tensor& src = batch.source;
    const torch::Tensor& tgt = batch.target;
    if (src.dim() != 3 || tgt.dim() != 3 || src.size(2) != 3 || tgt.size(2) != 3 ||
        src.size(0) != tgt.size(0) || src.size(1) < 1 || tgt.size(1) < 1) {
        throw std::invalid_argument("omnet: clouds must be [B, N, 3] and [B, M, 3], N, M >= 1");
    }
    const int64_t B = src.size(0), N = src.size(1), M = tgt.size(1);
    const auto opts = src.options();
    torch::Tensor pose = torch::zeros({B, 7}, opts);
    pose.select(1, 0).fill_(1.0);
    torch::Tensor src_mask = torch::ones({B, 1, N}, opts), tgt_mask = torch::ones({B, 1, M}, opts);
    const torch::Tensor tgt_points = tgt.transpose(1, 2);
    torch::Tensor moved = src;
    NetOutput out;
    for (int i = 0; i < config_.iterations; ++i) {
        if (i < config_.mask_delay) {
            src_mask = torch::ones({B, 1, N}, opts);
            tgt_mask = torch::ones({B, 1, M}, opts);
        }
        auto encoder = encoder_->ptr<OmnetEncoderImpl>(i);
        auto fusion = fusion_->ptr<OmnetFusionImpl>(i);
        auto decoder = decoder_->ptr<OmnetDecoderImpl>(i);
        const auto [src_local, src_global] =
            encoder->forward(moved.transpose(1, 2).detach(), src_mask);
        const auto [tgt_local, tgt_global] = encoder->forward(tgt_points, tgt_mask);
        const torch::Tensor src_fused =
            fusion->forward(src_local, src_global, tgt_global, src_mask);
        const torch::Tensor tgt_fused =
            fusion->forward(tgt_local, tgt_global, src_global, tgt_mask);
        const auto [src_hidden, src_logits] = decoder->forward(src_fused);
        const auto [tgt_hidden, tgt_logits] = decoder->forward(tgt_fused);
        // Max-pooled over each cloud's own points, then concatenated (see the header).
        const torch::Tensor pooled =
            torch::cat({std::get<0>(src_fused.max(2)), std::get<0>((src_hidden * src_mask).max(2)),
                        std::get<0>(tgt_fused.max(2)), std::get<0>((tgt_hidden * tgt_mask).max(2))},
                       1);
        const torch::Tensor step = regression_->ptr<OmnetRegressionImpl>(i)->forward(pooled);
        moved = torch::bmm(moved.detach(),
                           QuaternionToMatrix(step.index({Slice(), Slice(0, 4)})).transpose(1, 2)) +
                step.index({Slice(), Slice(4, 7)}).unsqueeze(1);
        pose = ComposePoses(pose.detach(), step);
        const std::string n = std::to_string(i);
        out.aux["logits_source_" + n] = src_logits;
        out.aux["logits_target_" + n] = tgt_logits;
        out.aux["mask_source_" + n] = src_mask.squeeze(1);
        out.aux["mask_target_" + n] = tgt_mask.squeeze(1);
        out.aux["pose_" + n] = pose;
        src_mask = src_logits.argmax(1, true).to(opts.dtype());
        tgt_mask = tgt_logits.argmax(1, true).to(opts.dtype());
    }
    out.T = torch::eye(4, opts).repeat({B, 1, 1});
    out.T.index_put_({Slice(), Slice(0, 3), Slice(0, 3)},
                     QuaternionToMatrix(pose.index({Slice(), Slice(0, 4)})));
    out.T.index_put_({Slice(), Slice(0, 3), 3}, pose.index({Slice(), Slice(4, 7)}));
    return out;
}

LossTerms OmnetNet::Loss(const PairBatch& batch, const NetOutput& output) {
    if (!batch.T_gt.defined()) throw std::invalid_argument("omnet loss: the batch has no T_gt");
    const torch::Tensor T = batch.T_gt.to(batch.source.dtype());
    const int64_t B = T.size(0);
    std::vector<double> gt(static_cast<size_t>(B) * 4);
    for (int64_t b = 0; b < B; ++b) {
        const auto q = QuaternionOf(T[b].index({Slice(0, 3), Slice(0, 3)}));
        std::copy(q.begin(), q.end(), gt.begin() + b * 4);
    }
    const torch::Tensor gt_quat =
        torch::tensor(gt, torch::kDouble).view({B, 4}).to(batch.source.dtype());
    const torch::Tensor gt_trans = T.index({Slice(), Slice(0, 3), 3});
    const torch::Tensor moved =
        torch::bmm(batch.source, T.index({Slice(), Slice(0, 3), Slice(0, 3)}).transpose(1, 2)) +
        gt_trans.unsqueeze(1);
    const torch::Tensor weights =
        torch::tensor({kNotOverlapWeight, kOverlapWeight}, batch.source.options());
    const auto ce = [&](const torch::Tensor& logits, const torch::Tensor& labels) {
        return F::cross_entropy(logits, labels, F::CrossEntropyFuncOptions().weight(weights));
    };
    LossTerms terms;
    torch::Tensor total = torch::zeros({}, batch.source.options());
    for (int i = 0; i < config_.iterations; ++i) {
        const std::string n = std::to_string(i);
        const torch::Tensor ms = output.aux.at("mask_source_" + n).detach();
        const torch::Tensor mt = output.aux.at("mask_target_" + n).detach();
        const torch::Tensor src_labels =
            OverlapLabels(moved, batch.target, ms, mt, config_.overlap_dist);
        const torch::Tensor tgt_labels =
            OverlapLabels(batch.target, moved, mt, ms, config_.overlap_dist);
        const torch::Tensor& pose = output.aux.at("pose_" + n);
        terms["overlap_" + n] = (ce(output.aux.at("logits_source_" + n), src_labels) +
                                 ce(output.aux.at("logits_target_" + n), tgt_labels)) /
                                2.0;
        terms["quat_" + n] =
            config_.quat_weight * (pose.index({Slice(), Slice(0, 4)}) - gt_quat).abs().mean();
        terms["trans_" + n] =
            config_.trans_weight * (pose.index({Slice(), Slice(4, 7)}) - gt_trans).pow(2).mean();
        total = total + terms["overlap_" + n] + terms["quat_" + n] + terms["trans_" + n];
    }
    terms["total"] = total;
    return terms;
}

std::map<std::string, int64_t> OmnetForwardMacs(const OmnetConfig& c, int64_t n, int64_t m) {
    const OmnetWidths w(c.width_divisor);
    const int64_t points = n + m, it = c.iterations;
    const int64_t encoder = 3 * w.w64 + 2 * w.w64 * w.w64 + w.w64 * w.w128 + w.w128 * w.w1024;
    const int64_t fusion_point = w.w64 * w.w1024 + w.w1024 * w.w1024 + w.w1024 * w.w512;
    const int64_t fusion_cloud = 2 * w.w1024 * w.w1024;
    const int64_t decoder = w.w512 * w.w512 + w.w512 * w.w256 + w.w256 * w.w256 + w.w256 * 2;
    const int64_t regression = 2 * (w.w512 + w.w1024) * w.w2048 + w.w2048 * w.w1024 +
                               w.w1024 * w.w512 + w.w512 * w.w256 + w.w256 * 7;
    return {{"encoder", it * points * encoder},
            {"fusion", it * (points * fusion_point + 2 * fusion_cloud)},
            {"decoder", it * points * decoder},
            {"regression", it * regression}};
}

}  // namespace regbench::networks
