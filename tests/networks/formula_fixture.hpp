#pragma once
// Deterministic weights and inputs shared with scripts/ogmm_reference.py (an independent PyTorch
// implementation of the same blocks): both sides fill every parameter and BatchNorm buffer from
// the same formula, so the C++ outputs can be pinned to the numbers PyTorch prints.
#include <torch/torch.h>

#include <cmath>
#include <string>

#include "core/transform.hpp"

namespace regbench::networks::testing {

/// 0.01 * (sum_k (k + 1) * code(name[k]) mod 997): a per-tensor phase from its name.
inline double FormulaPhase(const std::string& name) {
    long sum = 0;
    for (size_t k = 0; k < name.size(); ++k) {
        sum += static_cast<long>(k + 1) * static_cast<unsigned char>(name[k]);
    }
    return 0.01 * static_cast<double>(sum % 997);
}

inline bool EndsWith(const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

/// s = sin(0.37 i + 0.0013 i^2 + phase); conv weights s / sqrt(fan_in), norm scales 1 + 0.1 s,
/// biases 0.1 s, running means 0.1 s, running variances 1 + 0.5 s^2 (see the Python script).
inline void FormulaFill(torch::nn::Module& module) {
    torch::NoGradGuard no_grad;
    const auto fill = [](const std::string& name, torch::Tensor t) {
        if (EndsWith(name, "num_batches_tracked")) return;
        const torch::Tensor i = torch::arange(t.numel(), torch::kFloat64);
        const torch::Tensor s = torch::sin(0.37 * i + 0.0013 * i * i + FormulaPhase(name));
        torch::Tensor v;
        if (EndsWith(name, "running_mean")) {
            v = 0.1 * s;
        } else if (EndsWith(name, "running_var")) {
            v = 1 + 0.5 * s * s;
        } else if (t.dim() >= 2) {
            v = s / std::sqrt(static_cast<double>(t.numel()) / static_cast<double>(t.size(0)));
        } else if (EndsWith(name, "weight")) {
            v = 1 + 0.1 * s;
        } else {
            v = 0.1 * s;
        }
        t.copy_(v.view(t.sizes()).to(t.dtype()));
    };
    for (const auto& p : module.named_parameters()) fill(p.key(), p.value());
    for (const auto& b : module.named_buffers()) fill(b.key(), b.value());
}

/// Row-vector clouds [batch, n, 3]: point i of cloud b, s = seed + b:
/// (0.5 sin(0.9 i + s), 0.5 cos(1.7 i + 2 s), 0.5 sin(0.23 i + 0.013 i^2 + 3 s)).
inline torch::Tensor FormulaCloud(int64_t batch, int64_t n, double seed) {
    const torch::Tensor i = torch::arange(n, torch::kFloat64);
    std::vector<torch::Tensor> clouds;
    for (int64_t b = 0; b < batch; ++b) {
        const double s = seed + static_cast<double>(b);
        clouds.push_back(
            torch::stack({0.5 * torch::sin(0.9 * i + s), 0.5 * torch::cos(1.7 * i + 2 * s),
                          0.5 * torch::sin(0.23 * i + 0.013 * i * i + 3 * s)},
                         1));
    }
    return torch::stack(clouds).to(torch::kFloat);
}

/// T_gt [batch, 4, 4] (float) of pair b: rotation 0.3 + 0.2 b rad about (1, 2, 2) / 3, t = (0.1,
/// -0.2, 0.05 b).
inline torch::Tensor FormulaMotion(int64_t batch) {
    torch::Tensor T = torch::eye(4).repeat({batch, 1, 1});
    for (int64_t b = 0; b < batch; ++b) {
        const Eigen::Matrix3d R = RotationFromAxisAngle(Eigen::Vector3d(1, 2, 2) / 3.0,
                                                        0.3 + 0.2 * static_cast<double>(b));
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) T[b][r][c] = static_cast<float>(R(r, c));
        }
        T[b][0][3] = 0.1f;
        T[b][1][3] = -0.2f;
        T[b][2][3] = static_cast<float>(0.05 * static_cast<double>(b));
    }
    return T;
}

/// 0/1 labels [batch, n]: point i of cloud b overlaps when sin(0.5 i + b) > -0.2.
inline torch::Tensor FormulaLabels(int64_t batch, int64_t n) {
    const torch::Tensor i = torch::arange(n, torch::kFloat64);
    std::vector<torch::Tensor> rows;
    for (int64_t b = 0; b < batch; ++b) {
        rows.push_back((torch::sin(0.5 * i + static_cast<double>(b)) > -0.2).to(torch::kFloat));
    }
    return torch::stack(rows);
}

}  // namespace regbench::networks::testing
