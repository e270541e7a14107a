#include "networks/layers/layers.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/kd_tree.hpp"
#include "networks/layers/edge_stages.hpp"
#include "networks/layers/profile_scope.hpp"

namespace regbench::networks {
namespace {

namespace nn = torch::nn;
namespace F = torch::nn::functional;

constexpr double kLeakySlope = 0.2;  // SPE's LeakyReLU slope (the authors' code)
constexpr int64_t kSpeHidden = 64;   // SPE branch hidden width (the authors' code)

nn::Conv1d Conv1x1(int64_t in, int64_t out, bool bias) {
    return nn::Conv1d(nn::Conv1dOptions(in, out, 1).bias(bias));
}

nn::Conv2d Conv1x1_2d(int64_t in, int64_t out, bool bias) {
    return nn::Conv2d(nn::Conv2dOptions(in, out, 1).bias(bias));
}

void CheckChannelFirst(const torch::Tensor& x, int64_t channels, const char* who) {
    if (x.dim() != 3 || (channels > 0 && x.size(1) != channels)) {
        throw std::runtime_error(std::string(who) + ": expected a [B, " +
                                 (channels > 0 ? std::to_string(channels) : std::string("C")) +
                                 ", N] tensor, got " + std::to_string(x.dim()) + " dims");
    }
}

// The farthest-point loop shared by both starts: `distance` [B, N] is the running squared
// distance to the chosen set, `farthest` [B] the first index to take. A plain loop over the
// float data: as tensor ops it cost ~6 small ops per chosen point (LibTorch has no FPS op), which
// dominated the small configs' forward. Arithmetic as the tensor form did it: float squared
// differences summed over x, y, z in that order, ties to the lowest index.
torch::Tensor FarthestPointLoop(const torch::Tensor& xyz, const torch::Tensor& distance,
                                const torch::Tensor& farthest, int64_t n) {
    if (!xyz.device().is_cpu()) return FarthestPointTensorOps(xyz, distance, farthest, n);
    const int64_t batch = xyz.size(0), points = xyz.size(2);
    const torch::Tensor cloud = xyz.to(torch::kCPU, torch::kFloat).contiguous();  // [B, 3, N]
    // [B, N], updated in place: the caller's `distance` itself when already float on the CPU
    // (both callers pass a temporary).
    torch::Tensor running = distance.to(torch::kCPU, torch::kFloat).contiguous();
    const torch::Tensor start = farthest.to(torch::kCPU, torch::kLong).contiguous();
    torch::Tensor chosen = torch::empty({batch, n}, torch::kLong);
    for (int64_t b = 0; b < batch; ++b) {
        const float* x = cloud.data_ptr<float>() + b * 3 * points;
        const float *y = x + points, *z = y + points;
        float* d = running.data_ptr<float>() + b * points;
        int64_t* out = chosen.data_ptr<int64_t>() + b * n;
        int64_t next = start.data_ptr<int64_t>()[b];
        for (int64_t i = 0; i < n; ++i) {
            out[i] = next;
            const float cx = x[next], cy = y[next], cz = z[next];
            float best = -1.0f;
            for (int64_t j = 0; j < points; ++j) {
                const float dx = x[j] - cx, dy = y[j] - cy, dz = z[j] - cz;
                const float dj = std::min(d[j], dx * dx + dy * dy + dz * dz);
                d[j] = dj;
                if (dj > best) {
                    best = dj;
                    next = j;
                }
            }
        }
    }
    return chosen.to(xyz.device());
}

}  // namespace

// On a GPU the loop above would copy each cloud to the host and run on one core: a training
// step of the full config on an H200 was bound by such host loops (docs/learned-methods.md,
// "Training on a GPU machine"). There the same recurrence runs as n rounds of tensor ops.
torch::Tensor FarthestPointTensorOps(const torch::Tensor& xyz, const torch::Tensor& distance,
                                     const torch::Tensor& farthest, int64_t n) {
    const int64_t batch = xyz.size(0);
    const torch::Tensor cloud = xyz.to(torch::kFloat);   // [B, 3, N]
    torch::Tensor running = distance.to(torch::kFloat);  // replaced, never written in place
    torch::Tensor next = farthest.to(xyz.device(), torch::kLong).view({batch});
    std::vector<torch::Tensor> chosen;
    chosen.reserve(static_cast<std::size_t>(n));
    for (int64_t i = 0; i < n; ++i) {
        chosen.push_back(next);
        const torch::Tensor centre =
            cloud.gather(2, next.view({batch, 1, 1}).expand({batch, 3, 1}));
        running = torch::minimum(running, (cloud - centre).pow(2).sum(1));
        next = running.argmax(1);  // the first of equal maxima, as the loop's strict >
    }
    return torch::stack(chosen, 1);
}

namespace {

void CheckSampleCount(const torch::Tensor& xyz, int64_t n, const char* who) {
    CheckChannelFirst(xyz, 3, who);
    if (n < 1 || n > xyz.size(2)) {
        throw std::runtime_error(std::string(who) + ": cannot sample " + std::to_string(n) +
                                 " of " + std::to_string(xyz.size(2)) + " points");
    }
}

// kNN of 3-D points with nanoflann (exact double distances, closest first, so the point itself
// comes first): x [B, 3, N] -> [B, N, k]. The N x N distance matrix + topk it replaces cost
// ~20 ms per 717-point cloud, a tree ~1 ms.
torch::Tensor KnnIndices3d(const torch::Tensor& x, int64_t k) {
    const int64_t batch = x.size(0), points = x.size(2);
    const torch::Tensor rows =
        x.to(torch::kCPU, torch::kDouble).transpose(1, 2).contiguous();  // [B, N, 3]
    torch::Tensor idx = torch::empty({batch, points, k}, torch::kLong);
    std::vector<Eigen::Index> found;
    std::vector<double> sq;
    for (int64_t b = 0; b < batch; ++b) {
        const PointCloud cloud =
            Eigen::Map<const PointCloud>(rows.data_ptr<double>() + b * points * 3, points, 3);
        const KdTree tree(cloud);
        int64_t* out = idx.data_ptr<int64_t>() + b * points * k;
        for (int64_t i = 0; i < points; ++i) {
            tree.Knn(cloud.row(i).transpose(), static_cast<int>(k), found, sq);
            std::copy(found.begin(), found.end(), out + i * k);
        }
    }
    return idx.to(x.device());
}

// Max over the k neighbours of edges [..., k, C]. With a gradient to take, max with indices:
// its backward scatters the gradient to the argmax (one pass), where amax's backward builds an
// equality mask, counts ties and multiplies (four passes over the B N k C map, the mask
// converted to float on the way). The two differ only on exact positive ties, which the
// ReLU outputs meet when two neighbours coincide; at 0 ReLU's backward zeroes both anyway.
torch::Tensor MaxOverNeighbours(const torch::Tensor& edges) {
    if (torch::GradMode::is_enabled() && edges.requires_grad()) {
        return std::get<0>(edges.max(-2));
    }
    return edges.amax(-2);
}

}  // namespace

// One DGCNN stage on rows [M, in] (M = B N k edges or B N points, channels last): the 1x1 conv as
// a GEMM, BatchNorm, ReLU. In eval mode BatchNorm is folded into the GEMM's weights and bias
// (W' = W g / sqrt(var + eps), b' = beta - mean g / sqrt(var + eps)), so one addmm and one
// in-place ReLU touch the [M, out] map. In training mode the batch statistics over the M rows
// are those BatchNorm2d takes over (B, N, k).
torch::Tensor RowsConvBnRelu(const torch::Tensor& rows, const torch::nn::Conv2d& conv,
                             const torch::nn::BatchNorm2d& bn) {
    const torch::Tensor w = conv->weight.view({conv->weight.size(0), conv->weight.size(1)});
    const auto& o = bn->options;
    if (!bn->is_training()) {
        const torch::Tensor scale = bn->weight * torch::rsqrt(bn->running_var + o.eps());
        const torch::Tensor bias = bn->bias - bn->running_mean * scale;
        return torch::addmm(bias, rows, (w * scale.unsqueeze(1)).t()).relu_();
    }
    {
        torch::NoGradGuard no_grad;
        bn->num_batches_tracked.add_(1);  // as BatchNorm2d::forward counts its batches
    }
    const double momentum = o.momentum().has_value() ? o.momentum().value() : 0.1;
    // In place: BatchNorm's backward needs its input and batch statistics, not its output.
    return torch::batch_norm(torch::mm(rows, w.t()), bn->weight, bn->bias, bn->running_mean,
                             bn->running_var, /*training=*/true, momentum, o.eps(),
                             /*cudnn_enabled=*/false)
        .relu_();
}

Conv3Impl::Conv3Impl(int64_t in_channels, int64_t out_channels, int64_t hidden_channels) {
    conv1_ = register_module("conv1", Conv1x1(in_channels, hidden_channels, true));
    bn1_ = register_module("bn1", nn::BatchNorm1d(hidden_channels));
    conv2_ = register_module("conv2", Conv1x1(hidden_channels, hidden_channels, true));
    bn2_ = register_module("bn2", nn::BatchNorm1d(hidden_channels));
    conv3_ = register_module("conv3", Conv1x1(hidden_channels, out_channels, true));
}

torch::Tensor Conv3Impl::forward(const torch::Tensor& x) {
    torch::Tensor h = torch::relu(bn1_(conv1_(x)));
    h = torch::relu(bn2_(conv2_(h)));
    return conv3_(h);
}

Conv2Impl::Conv2Impl(int64_t in_channels, int64_t out_channels, int64_t hidden_channels) {
    conv1_ = register_module("conv1", Conv1x1(in_channels, hidden_channels, true));
    bn1_ = register_module("bn1", nn::BatchNorm1d(hidden_channels));
    conv2_ = register_module("conv2", Conv1x1(hidden_channels, out_channels, true));
}

torch::Tensor Conv2Impl::forward(const torch::Tensor& x) {
    return conv2_(torch::relu(bn1_(conv1_(x))));
}

torch::Tensor FpsRandom(const torch::Tensor& xyz, int64_t n,
                        c10::optional<at::Generator> generator) {
    CheckSampleCount(xyz, n, "FpsRandom");
    torch::NoGradGuard no_grad;
    // The start indices are drawn on the CPU, where the loop runs, whatever device xyz is on:
    // a CPU generator then serves a GPU forward too.
    torch::Tensor start = torch::randint(xyz.size(2), {xyz.size(0)}, generator, torch::kLong);
    torch::Tensor distance = torch::full({xyz.size(0), xyz.size(2)}, 1e10, xyz.options());
    return FarthestPointLoop(xyz, distance, start, n);
}

torch::Tensor FpsCentroid(const torch::Tensor& xyz, int64_t n) {
    CheckSampleCount(xyz, n, "FpsCentroid");
    torch::NoGradGuard no_grad;
    torch::Tensor distance = (xyz - xyz.mean(2, true)).pow(2).sum(1);  // [B, N]
    torch::Tensor start = std::get<1>(distance.max(1));
    return FarthestPointLoop(xyz, distance, start, n);
}

torch::Tensor GatherColumns(const torch::Tensor& x, const torch::Tensor& idx) {
    return torch::gather(x, 2, idx.unsqueeze(1).expand({x.size(0), x.size(1), idx.size(1)}));
}

torch::Tensor KnnIndices(const torch::Tensor& x, int64_t k) {
    CheckChannelFirst(x, 0, "KnnIndices");
    if (k < 1 || k > x.size(2)) {
        throw std::runtime_error("KnnIndices: k = " + std::to_string(k) + " neighbours of " +
                                 std::to_string(x.size(2)) + " points");
    }
    torch::NoGradGuard no_grad;
    // nanoflann on the host for 3-D points on the CPU; on a GPU the distance matrix below.
    if (x.size(1) == 3 && x.device().is_cpu()) return KnnIndices3d(x, k);
    // -|xi - xj|^2 = -|xi|^2 + 2 xi.xj - |xj|^2, the largest k are the nearest.
    const torch::Tensor inner = -2 * torch::matmul(x.transpose(2, 1), x);
    const torch::Tensor xx = x.pow(2).sum(1, true);
    const torch::Tensor neg_d2 = -xx - inner - xx.transpose(2, 1);
    return std::get<1>(neg_d2.topk(k, -1));
}

torch::Tensor EdgeFeatures(const torch::Tensor& x, const torch::Tensor& idx) {
    const int64_t batch = x.size(0), channels = x.size(1), points = x.size(2), k = idx.size(2);
    const torch::Tensor rows = x.transpose(2, 1).contiguous();  // [B, N, C]
    const torch::Tensor base = torch::arange(batch, idx.options()).view({-1, 1, 1}) * points;
    const torch::Tensor flat = (idx + base).view({-1});
    const torch::Tensor neighbours = rows.view({batch * points, channels})
                                         .index_select(0, flat)
                                         .view({batch, points, k, channels});
    const torch::Tensor centre = rows.view({batch, points, 1, channels}).expand_as(neighbours);
    return torch::cat({neighbours - centre, centre}, 3).permute({0, 3, 1, 2});
}

DgcnnImpl::DgcnnImpl(int64_t emb_dims, int64_t k) : k_(k) {
    conv1_ = register_module("conv1", Conv1x1_2d(6, 64, false));
    conv2_ = register_module("conv2", Conv1x1_2d(64, 64, false));
    conv3_ = register_module("conv3", Conv1x1_2d(64, 128, false));
    conv4_ = register_module("conv4", Conv1x1_2d(128, 256, false));
    conv5_ = register_module("conv5", Conv1x1_2d(512, emb_dims, false));
    bn1_ = register_module("bn1", nn::BatchNorm2d(64));
    bn2_ = register_module("bn2", nn::BatchNorm2d(64));
    bn3_ = register_module("bn3", nn::BatchNorm2d(128));
    bn4_ = register_module("bn4", nn::BatchNorm2d(256));
    bn5_ = register_module("bn5", nn::BatchNorm2d(emb_dims));
}

torch::Tensor DgcnnImpl::forward(const torch::Tensor& xyz) {
    CheckChannelFirst(xyz, 3, "Dgcnn");
    REGBENCH_PROFILE_SCOPE("networks::dgcnn");
    // Channels last: every edge is a row, so each 1x1 conv is one GEMM over B N k rows and the
    // max over the k neighbours reduces a strided dimension with the channels contiguous. The
    // channel-first form (Conv2d on [B, C, N, k], amax over the innermost k) spent most of its
    // time in the amax and in the convolution's input copies (docs/performance.md).
    const int64_t batch = xyz.size(0), points = xyz.size(2);
    const torch::Tensor x = EdgeFeatures(xyz, KnnIndices(xyz, k_))  // [B, 6, N, k]
                                .permute({0, 2, 3, 1})
                                .reshape({batch * points * k_, 6});
    const torch::Tensor cat = PooledEdgeStages(
        x, {{conv1_, bn1_}, {conv2_, bn2_}, {conv3_, bn3_}, {conv4_, bn4_}}, k_);  // [BN, 512]
    return RowsConvBnRelu(cat, conv5_, bn5_).view({batch, points, -1}).transpose(1, 2);
}

torch::Tensor PooledEdgeStages(torch::Tensor rows,
                               const std::vector<std::pair<nn::Conv2d, nn::BatchNorm2d>>& stages,
                               int64_t k) {
    const bool training = !stages.empty() && stages.front().second->is_training();
    if (training && rows.device().is_cpu() &&
        (rows.scalar_type() == torch::kFloat || rows.scalar_type() == torch::kDouble)) {
        // Training: the edge stages with batch statistics (networks/layers/edge_stages.hpp), fused
        // into one autograd Function unless a test asks for the LibTorch composition.
        std::vector<EdgeStage> edge_stages;
        for (const auto& [conv, bn] : stages) edge_stages.push_back(EdgeStageOf(conv, bn));
        return FusedEdgeStages() ? EdgeStagesFused(rows, edge_stages, k)
                                 : EdgeStagesReference(rows, edge_stages, k);
    }
    const int64_t points = rows.size(0) / k;
    std::vector<torch::Tensor> pooled;
    for (const auto& [conv, bn] : stages) {
        rows = RowsConvBnRelu(rows, conv, bn);
        pooled.push_back(MaxOverNeighbours(rows.view({points, k, rows.size(1)})));
    }
    return torch::cat(pooled, 1);
}

AttentionalPropagationImpl::AttentionalPropagationImpl(int64_t feature_dim, int64_t num_heads)
    : heads_(num_heads) {
    if (num_heads < 1 || feature_dim % num_heads != 0) {
        throw std::runtime_error("AttentionalPropagation: feature dim " +
                                 std::to_string(feature_dim) + " is not divisible by " +
                                 std::to_string(num_heads) + " heads");
    }
    merge_ = register_module("merge", Conv1x1(feature_dim, feature_dim, true));
    proj_ = register_module("proj", nn::ModuleList());
    for (int i = 0; i < 3; ++i) {
        auto conv = Conv1x1(feature_dim, feature_dim, true);
        torch::NoGradGuard no_grad;  // deepcopy(merge) in the reference
        conv->weight.copy_(merge_->weight);
        conv->bias.copy_(merge_->bias);
        proj_->push_back(conv);
    }
    mlp_ = register_module(
        "mlp", nn::Sequential(Conv1x1(2 * feature_dim, 2 * feature_dim, true),
                              nn::InstanceNorm1d(nn::InstanceNorm1dOptions(2 * feature_dim)),
                              nn::ReLU(), Conv1x1(2 * feature_dim, feature_dim, true)));
    torch::NoGradGuard no_grad;
    mlp_[3]->as<nn::Conv1d>()->bias.zero_();
}

torch::Tensor AttentionalPropagationImpl::forward(const torch::Tensor& x,
                                                  const torch::Tensor& source) {
    const int64_t batch = x.size(0), dim = x.size(1) / heads_;
    const auto project = [&](int which, const torch::Tensor& in) {
        return proj_[which]->as<nn::Conv1d>()->forward(in).view({batch, dim, heads_, -1});
    };
    const torch::Tensor query = project(0, x);
    const torch::Tensor key = project(1, source);
    const torch::Tensor value = project(2, source);
    const torch::Tensor scores =
        torch::einsum("bdhn,bdhm->bhnm", {query, key}) / std::sqrt(static_cast<double>(dim));
    const torch::Tensor prob = torch::softmax(scores, -1);
    const torch::Tensor message = torch::einsum("bhnm,bdhm->bdhn", {prob, value})
                                      .contiguous()
                                      .view({batch, dim * heads_, -1});
    return mlp_->forward(torch::cat({x, merge_(message)}, 1));
}

SphericalEncodingImpl::SphericalEncodingImpl(int64_t out_channels, int64_t k_angle)
    : k_angle_(k_angle) {
    if (out_channels % 2 != 0) {
        throw std::runtime_error("SphericalEncoding: output channels " +
                                 std::to_string(out_channels) + " must be even");
    }
    const int64_t half = out_channels / 2;
    const auto leaky = [] {
        return nn::LeakyReLU(nn::LeakyReLUOptions().negative_slope(kLeakySlope));
    };
    dist_ = register_module(
        "dist", nn::Sequential(Conv1x1(1, kSpeHidden, false), nn::BatchNorm1d(kSpeHidden), leaky(),
                               Conv1x1(kSpeHidden, half, false), nn::BatchNorm1d(half), leaky()));
    angle_2d_ = register_module("angle_2d", nn::Sequential(Conv1x1_2d(1, kSpeHidden, false),
                                                           nn::BatchNorm2d(kSpeHidden), leaky()));
    angle_1d_ = register_module("angle_1d", nn::Sequential(Conv1x1(kSpeHidden, half, false),
                                                           nn::BatchNorm1d(half), leaky()));
    unused_conv_ = register_module("unused_conv", Conv1x1(out_channels, out_channels, false));
    unused_bn_ = register_module("unused_bn", nn::BatchNorm1d(out_channels));
}

torch::Tensor SphericalEncodingImpl::forward(const torch::Tensor& xyz) {
    CheckChannelFirst(xyz, 3, "SphericalEncoding");
    const torch::Tensor radial = xyz - xyz.mean(2, true);  // p_i - c, [B, 3, N]
    const torch::Tensor dist = dist_->forward(radial.pow(2).sum(1, true));
    const torch::Tensor idx = KnnIndices(xyz, k_angle_);  // [B, N, k], self first
    const torch::Tensor neighbours = EdgeFeatures(xyz, idx).slice(1, 0, 3);  // p_k - p_i
    // cos angle(p_k - p_i, p_i - c); the self neighbour is a zero vector and gives 0.
    const torch::Tensor cosines =
        F::cosine_similarity(neighbours, radial.unsqueeze(-1).expand_as(neighbours),
                             F::CosineSimilarityFuncOptions().dim(1));  // [B, N, k]
    const torch::Tensor angle = angle_2d_->forward(cosines.unsqueeze(1)).amax(-1);
    return torch::cat({dist, angle_1d_->forward(angle)}, 1);
}

int64_t CountParameters(const torch::nn::Module& module) {
    int64_t count = 0;
    for (const auto& p : module.parameters()) count += p.numel();
    return count;
}

void LoadStrictStateDict(torch::nn::Module& module,
                         const std::vector<std::pair<std::string, torch::Tensor>>& tensors,
                         const std::string& file, const std::string& network) {
    std::vector<std::pair<std::string, torch::Tensor>> own;
    for (const auto& p : module.named_parameters()) own.emplace_back(p.key(), p.value());
    for (const auto& b : module.named_buffers()) own.emplace_back(b.key(), b.value());
    std::set<std::string> known;
    for (const auto& kv : own) known.insert(kv.first);
    for (const auto& kv : tensors) {
        if (known.count(kv.first) == 0) {
            throw std::runtime_error(file + ": tensor " + kv.first + " is not in " + network +
                                     "'s state dict");
        }
    }
    torch::NoGradGuard no_grad;
    for (auto& [key, value] : own) {
        const auto found = std::find_if(tensors.begin(), tensors.end(),
                                        [&key = key](const auto& kv) { return kv.first == key; });
        if (found == tensors.end()) {
            throw std::runtime_error(file + ": has no tensor " + key + " (" + network +
                                     " state dict)");
        }
        if (found->second.sizes() != value.sizes()) {
            throw std::runtime_error(file + ": tensor " + key + " has shape " +
                                     c10::str(found->second.sizes()) + ", " + network + "'s is " +
                                     c10::str(value.sizes()));
        }
        value.copy_(found->second.to(value.dtype()));
    }
}

}  // namespace regbench::networks
