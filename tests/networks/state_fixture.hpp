#pragma once
// Small readers the network tests share (test code, in regbench::networks beside the networks): a
// module's state-dict shapes by key, and a tensor from the nested JSON arrays the PyTorch stand-ins
// print.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace regbench::networks {

/// Every parameter's and buffer's shape by its state-dict key.
inline std::map<std::string, std::vector<int64_t>> StateShapes(const torch::nn::Module& net) {
    std::map<std::string, std::vector<int64_t>> shapes;
    for (const auto& p : net.named_parameters()) shapes[p.key()] = p.value().sizes().vec();
    for (const auto& b : net.named_buffers()) shapes[b.key()] = b.value().sizes().vec();
    return shapes;
}

/// Expects every key of `theirs` (shapes read off the authors' modules) in `shapes` with its
/// shape.
inline void ExpectShapesInclude(const std::map<std::string, std::vector<int64_t>>& shapes,
                                const std::map<std::string, std::vector<int64_t>>& theirs) {
    for (const auto& [key, shape] : theirs) {
        const auto it = shapes.find(key);
        EXPECT_TRUE(it != shapes.end()) << key;
        if (it != shapes.end()) {
            EXPECT_EQ(it->second, shape) << key;
        }
    }
}

/// A float64 tensor from nested JSON arrays of numbers; the shape from the nesting.
inline torch::Tensor TensorFromJson(const nlohmann::json& j) {
    std::vector<double> flat;
    std::vector<int64_t> shape;
    const nlohmann::json* level = &j;
    while (level->is_array()) {
        shape.push_back(static_cast<int64_t>(level->size()));
        if (level->empty()) break;
        level = &(*level)[0];
    }
    const std::function<void(const nlohmann::json&)> walk = [&](const nlohmann::json& v) {
        if (v.is_array()) {
            for (const auto& x : v) walk(x);
        } else {
            flat.push_back(v.get<double>());
        }
    };
    walk(j);
    return torch::tensor(flat, torch::kDouble).view(shape);
}

}  // namespace regbench::networks
