#pragma once
// Building blocks shared by OGMM and the paper's DeepGMR variant (LibTorch). Every block works on
// channel-first tensors [B, C, N] like the authors' PyTorch code; callers holding row-vector
// clouds [B, N, 3] transpose once. Submodule names follow the PyTorch modules they mirror, so a
// state dict maps one to one (scripts/ogmm_reference.py rebuilds the same blocks in PyTorch).
#include <torch/torch.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace regbench::networks {

/// Three 1x1 convolutions with bias: in -> hidden (BN, ReLU) -> hidden (BN, ReLU) -> out.
/// BatchNorm uses PyTorch's defaults (eps 1e-5, momentum 0.1).
class Conv3Impl : public torch::nn::Module {
public:
    Conv3Impl(int64_t in_channels, int64_t out_channels, int64_t hidden_channels);
    torch::Tensor forward(const torch::Tensor& x);  ///< [B, in, N] -> [B, out, N]

private:
    torch::nn::Conv1d conv1_{nullptr}, conv2_{nullptr}, conv3_{nullptr};
    torch::nn::BatchNorm1d bn1_{nullptr}, bn2_{nullptr};
};
TORCH_MODULE(Conv3);

/// Two 1x1 convolutions with bias: in -> hidden (BN, ReLU) -> out.
class Conv2Impl : public torch::nn::Module {
public:
    Conv2Impl(int64_t in_channels, int64_t out_channels, int64_t hidden_channels);
    torch::Tensor forward(const torch::Tensor& x);  ///< [B, in, N] -> [B, out, N]

private:
    torch::nn::Conv1d conv1_{nullptr}, conv2_{nullptr};
    torch::nn::BatchNorm1d bn1_{nullptr};
};
TORCH_MODULE(Conv2);

/// Farthest point sampling from a random start: xyz [B, 3, N] -> indices [B, n] (int64). The
/// start index of each cloud is drawn with torch::randint from `generator` (the torch global
/// RNG when none is given), one draw of shape [B]. Each next point is the one farthest (squared
/// distance) from the points chosen so far; ties go to the lowest index. Throws when n > N.
torch::Tensor FpsRandom(const torch::Tensor& xyz, int64_t n,
                        c10::optional<at::Generator> generator = c10::nullopt);

/// Farthest point sampling from the centroid (deterministic): starts at the point farthest from
/// the cloud's mean, with the running distance initialised to the squared distance to the mean.
torch::Tensor FpsCentroid(const torch::Tensor& xyz, int64_t n);

/// The farthest-point recurrence of FpsRandom / FpsCentroid as tensor ops, which they use on a
/// GPU (on the CPU a plain loop): `distance` [B, N] the running squared distance to the chosen
/// set, `farthest` [B] the first index. Same arithmetic and ties (lowest index) as the loop.
torch::Tensor FarthestPointTensorOps(const torch::Tensor& xyz, const torch::Tensor& distance,
                                     const torch::Tensor& farthest, int64_t n);

/// Gathers columns: x [B, C, N], idx [B, n] -> [B, C, n].
torch::Tensor GatherColumns(const torch::Tensor& x, const torch::Tensor& idx);

/// Indices of the k nearest neighbours of every point (the point itself first): x [B, C, N] ->
/// [B, N, k] (int64), by squared Euclidean distance in C dimensions.
torch::Tensor KnnIndices(const torch::Tensor& x, int64_t k);

/// DGCNN edge features [x_j - x_i, x_i] over the neighbours idx [B, N, k]: x [B, C, N] ->
/// [B, 2C, N, k].
torch::Tensor EdgeFeatures(const torch::Tensor& x, const torch::Tensor& idx);

/// One bias-free 1x1 Conv2d, its BatchNorm2d and ReLU on rows [M, in] (channels last) -> [M, out].
/// In eval mode BatchNorm is folded into the GEMM; in training mode it takes the batch statistics
/// over the M rows (what BatchNorm2d takes over B, N, k) and updates the running ones.
torch::Tensor RowsConvBnRelu(const torch::Tensor& rows, const torch::nn::Conv2d& conv,
                             const torch::nn::BatchNorm2d& bn);

/// DGCNN edge stages: rows [P k, C0] of P points' k edges (k consecutive rows per point) go
/// through the chain of RowsConvBnRelu `stages`; each stage's output is max-pooled over the k
/// neighbours and the pooled maps are concatenated: [P, C1 + C2 + ...]. In training on the CPU
/// (float or double) the chain runs as EdgeStagesFused (networks/layers/edge_stages.hpp) unless
/// SetFusedEdgeStages(false).
torch::Tensor PooledEdgeStages(
    torch::Tensor rows,
    const std::vector<std::pair<torch::nn::Conv2d, torch::nn::BatchNorm2d>>& stages, int64_t k);

/// Static DGCNN as in DCP: the kNN graph is built once on xyz; edge features go through a chain
/// of bias-free Conv2d 6->64->64->128->256 (each BN2d + ReLU), every stage is max-pooled over
/// the k neighbours, the four maps are concatenated (512 channels) and a bias-free 1x1 conv to
/// emb_dims (BN + ReLU) gives the per-point features.
class DgcnnImpl : public torch::nn::Module {
public:
    DgcnnImpl(int64_t emb_dims, int64_t k);
    torch::Tensor forward(const torch::Tensor& xyz);  ///< [B, 3, N] -> [B, emb_dims, N]

    int64_t k() const { return k_; }

private:
    int64_t k_;
    torch::nn::Conv2d conv1_{nullptr}, conv2_{nullptr}, conv3_{nullptr}, conv4_{nullptr},
        conv5_{nullptr};
    torch::nn::BatchNorm2d bn1_{nullptr}, bn2_{nullptr}, bn3_{nullptr}, bn4_{nullptr},
        bn5_{nullptr};
};
TORCH_MODULE(Dgcnn);

/// SuperGlue-style multi-head attention message passing. Q/K/V are 1x1 convs with bias;
/// channels are split into heads interleaved (channel c -> head c mod H, slot c div H); per head
/// P = softmax over the keys of Q^T K / sqrt(d/H); the merged message goes through `merge`, and
/// the update is Conv(2d->d)(ReLU(InstanceNorm(Conv(2d->2d)(cat[x, message])))). The caller adds
/// the residual. At construction the Q/K/V projections copy merge's initial weights and the last
/// conv's bias is zero, as the reference does.
class AttentionalPropagationImpl : public torch::nn::Module {
public:
    AttentionalPropagationImpl(int64_t feature_dim, int64_t num_heads);
    /// x [B, d, N] attends to source [B, d, A] -> update [B, d, N].
    torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& source);

private:
    int64_t heads_;
    torch::nn::Conv1d merge_{nullptr};
    torch::nn::ModuleList proj_{nullptr};  ///< query, key, value projections
    torch::nn::Sequential mlp_{nullptr};
};
TORCH_MODULE(AttentionalPropagation);

/// OGMM's spherical positional encoding (the authors' code): with c the cloud's mean,
/// a distance branch on |p_i - c|^2 (Conv1d 1->64, BN, LeakyReLU .2, 64->out/2, BN, LeakyReLU)
/// and an angle branch on cos angle(p_k - p_i, p_i - c) over the k_angle nearest neighbours
/// (Conv2d 1->64, BN2d, LeakyReLU, max over k, Conv1d 64->out/2, BN, LeakyReLU); the two are
/// concatenated. All convs are bias-free. The reference also builds a 1x1 Conv out->out + BN it
/// never uses; it is kept (`unused_conv`, `unused_bn`) so parameter counts and state dicts match.
class SphericalEncodingImpl : public torch::nn::Module {
public:
    SphericalEncodingImpl(int64_t out_channels, int64_t k_angle);
    torch::Tensor forward(const torch::Tensor& xyz);  ///< [B, 3, N] -> [B, out, N]

private:
    int64_t k_angle_;
    torch::nn::Sequential dist_{nullptr};
    torch::nn::Sequential angle_2d_{nullptr};
    torch::nn::Sequential angle_1d_{nullptr};
    torch::nn::Conv1d unused_conv_{nullptr};
    torch::nn::BatchNorm1d unused_bn_{nullptr};
};
TORCH_MODULE(SphericalEncoding);

/// Number of trainable scalars of a module (what the paper's parameter counts count).
int64_t CountParameters(const torch::nn::Module& module);

/// Copies `tensors` (name, tensor) into the parameters and buffers of `module` of the same
/// names: every one must be present with its shape, and no other may be; throws
/// std::runtime_error "<file>: ..." naming the first offending key and `network`.
void LoadStrictStateDict(torch::nn::Module& module,
                         const std::vector<std::pair<std::string, torch::Tensor>>& tensors,
                         const std::string& file, const std::string& network);

}  // namespace regbench::networks
