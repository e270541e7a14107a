#include "networks/families/deepgmr/net.hpp"

#include <stdexcept>

#include "networks/family_config.hpp"
#include "networks/layers/gmm_head.hpp"

namespace regbench::networks {
namespace {

using torch::indexing::Slice;

/// CBR(i, o): 1x1 Conv1d without bias -> BatchNorm1d -> ReLU (the original's building block).
/// Children "0" and "1" give the original's state-dict keys (encoder.0.0.weight, ...).
class CbrImpl : public torch::nn::Module {
public:
    CbrImpl(int in, int out) {
        conv_ = register_module(
            "0", torch::nn::Conv1d(torch::nn::Conv1dOptions(in, out, 1).bias(false)));
        bn_ = register_module("1", torch::nn::BatchNorm1d(
                                       torch::nn::BatchNorm1dOptions(out).eps(1e-5).momentum(0.1)));
    }
    torch::Tensor forward(const torch::Tensor& x) {
        return torch::relu(bn_->forward(conv_->forward(x)));
    }

private:
    torch::nn::Conv1d conv_{nullptr};
    torch::nn::BatchNorm1d bn_{nullptr};
};
TORCH_MODULE(Cbr);

torch::Tensor Rotation(const torch::Tensor& T) {
    return T.index({Slice(), Slice(0, 3), Slice(0, 3)});
}
torch::Tensor Translation(const torch::Tensor& T) { return T.index({Slice(), Slice(0, 3), 3}); }

}  // namespace

// Ranges: the original's models have J 16, d_model 1024, rri_k 20; the OGMM paper's variant
// J 128, DGCNN width 512, head 256, k 20 (wentaoyuan/deepgmr, gfmei/ogmm). The bounds are 4
// (widths) to 8 (J) times those: no trained configuration comes near them, and a network built
// above them would not fit in memory (clusters 1e9 asks for terabytes), so a checkpoint or an
// authors' file with such a size is refused before anything is built.
void DeepGmrConfig::Validate(ParamCheck& c) const {
    InRange(c, "clusters", clusters, 1, 1024);
    InRange(c, "rri_k", rri_k, 2, 128);
    InRange(c, "d_model", d_model, 1, 4096);
    InRange(c, "emb_dims", emb_dims, 1, 4096);
    InRange(c, "dgcnn_k", dgcnn_k, 1, 128);
    InRange(c, "head_hidden", head_hidden, 1, 4096);
}

nlohmann::json ToJson(const DeepGmrConfig& c) {
    nlohmann::json j = NetConfigJson(c, "deepgmr");
    if (c.d_model == 1024) j.erase("d_model");
    return j;
}

DeepGmrConfig DeepGmrConfigFromJson(const nlohmann::json& j) {
    return ParseNetConfig<DeepGmrConfig>(j, "deepgmr");
}

DeepGmrNet::DeepGmrNet(const DeepGmrConfig& config) : config_(config) {
    const int J = config_.clusters;
    if (config_.features == DeepGmrFeatures::kDgcnn) {
        dgcnn_ = register_module("dgcnn", Dgcnn(config_.emb_dims, config_.dgcnn_k));
        head_ = register_module("head", Conv3(config_.emb_dims, J, config_.head_hidden));
        return;
    }
    const int d_in = config_.features == DeepGmrFeatures::kRri ? 4 * config_.rri_k : 3;
    // Module tree backbone.{encoder,decoder}.* mirrors the original's state-dict keys.
    auto backbone = register_module("backbone", std::make_shared<torch::nn::Module>());
    const int d = config_.d_model;
    encoder_ = torch::nn::Sequential(Cbr(d_in, 64), Cbr(64, 128), Cbr(128, 256), Cbr(256, d));
    decoder_ = torch::nn::Sequential(Cbr(2 * d, 512), Cbr(512, 256), Cbr(256, 128),
                                     torch::nn::Conv1d(torch::nn::Conv1dOptions(128, J, 1)));
    backbone->register_module("encoder", encoder_);
    backbone->register_module("decoder", decoder_);
}

torch::Tensor DeepGmrNet::Assign(const torch::Tensor& xyz) {
    torch::Tensor logits;  // [B, J, N]
    if (config_.features == DeepGmrFeatures::kDgcnn) {
        logits = head_->forward(dgcnn_->forward(xyz.transpose(1, 2).contiguous()));
    } else {
        torch::Tensor input;
        if (config_.features == DeepGmrFeatures::kRri) {
            input = RriFeatureTensor(xyz, config_.rri_k, config_.rri_variant);
        } else {
            input = (xyz - xyz.mean(1, true)).transpose(1, 2).contiguous();
        }
        const torch::Tensor local = encoder_->forward(input);  // [B, d_model, N]
        const torch::Tensor global = std::get<0>(local.max(2, true)).expand_as(local);
        logits = decoder_->forward(torch::cat({local, global}, 1));
    }
    return torch::softmax(logits.transpose(1, 2), 2);
}

NetOutput DeepGmrNet::Forward(const PairBatch& batch) {
    // Two separate calls, as the original: BatchNorm sees each cloud's batch on its own.
    const torch::Tensor gamma_s = Assign(batch.source);
    const torch::Tensor gamma_t = Assign(batch.target);
    const GmmParams gs = ComputeGmmParams(gamma_s, batch.source);
    const GmmParams gt = ComputeGmmParams(gamma_t, batch.target);
    NetOutput out;
    out.T = GmmRegister(gs.pi, gs.mu, gt.mu, gt.sigma);
    out.aux["T21"] = GmmRegister(gt.pi, gt.mu, gs.mu, gs.sigma);
    out.aux["gamma_source"] = gamma_s;
    out.aux["gamma_target"] = gamma_t;
    out.aux["pi_source"] = gs.pi;
    out.aux["pi_target"] = gt.pi;
    return out;
}

LossTerms DeepGmrNet::Loss(const PairBatch& batch, const NetOutput& output) {
    TORCH_CHECK(batch.T_gt.defined(), "DeepGmrNet::Loss needs T_gt");
    LossTerms terms;
    if (config_.loss == DeepGmrLoss::kTransform) {
        const torch::Tensor eye = torch::eye(4, output.T.options()).expand_as(output.T);
        terms["T12"] = (torch::bmm(output.T, torch::inverse(batch.T_gt)) - eye).pow(2).mean();
        terms["T21"] = (torch::bmm(output.aux.at("T21"), batch.T_gt) - eye).pow(2).mean();
        terms["total"] = terms["T12"] + terms["T21"];
    } else {
        const torch::Tensor R = Rotation(output.T);
        const torch::Tensor eye = torch::eye(3, R.options()).expand_as(R);
        terms["rotation"] =
            (torch::bmm(R.transpose(1, 2), Rotation(batch.T_gt)) - eye).pow(2).mean();
        terms["translation"] = (Translation(output.T) - Translation(batch.T_gt)).pow(2).mean();
        terms["total"] = terms["rotation"] + terms["translation"];
    }
    return terms;
}

}  // namespace regbench::networks
