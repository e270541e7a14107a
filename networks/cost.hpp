#pragma once
// Analytic cost of one forward pass of a learned network (paper Tab. 6's "model cost"): the
// multiply-accumulates of its convolutions and matrix products for a batch-1 pair, computed from
// the config alone (no network is built). The formulas are in docs/learned-methods.md ("Cost").
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

namespace regbench::networks {

/// Multiply-accumulates (MACs) of one forward on a pair, by part and in total.
struct ForwardCost {
    std::int64_t total = 0;                     ///< sum of `parts`
    std::map<std::string, std::int64_t> parts;  ///< e.g. "dgcnn", "attention", "gmm_fit"
};

/// MACs of one batch-1 forward of the network `config` describes (a zoo config; its family,
/// networks/family.hpp FamilyOfConfig, counts) on a source of `source_points` and a target of
/// `target_points` points. Counts every convolution and matrix product (1x1 convs,
/// kNN Gram matrices, attention scores and messages, mixture statistics, distances of FPS and
/// of the GMM fit); element-wise work (BatchNorm, activations, softmax, Sinkhorn's exp/log,
/// RRI's trigonometry, kd-tree searches) is not counted. Throws std::invalid_argument naming a
/// missing key or a non-positive point count.
ForwardCost ComputeForwardCost(const nlohmann::json& config, std::int64_t source_points,
                               std::int64_t target_points);

// Building blocks of the families' counts (networks/families/<family>/family.cpp).

/// The integer `key` of `config`; throws std::invalid_argument naming a missing key.
std::int64_t CostKey(const nlohmann::json& config, const char* key);
/// Adds `macs` to `cost.parts[part]` and to the total.
void AddMacs(ForwardCost& cost, const std::string& part, std::int64_t macs);
/// A ForwardCost from MACs by part (a "total" entry, if any, is recomputed, not added).
ForwardCost CostOfParts(const std::map<std::string, std::int64_t>& parts);
/// Static DGCNN on n points with k neighbours and output width d: edge convs 6->64->64->128->256
/// on n k edges, the 512 -> d conv per point, and the kNN Gram matrix (3 n^2).
std::int64_t DgcnnMacs(std::int64_t n, std::int64_t k, std::int64_t d);

}  // namespace regbench::networks
