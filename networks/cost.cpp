#include "networks/cost.hpp"

#include <stdexcept>

#include "networks/family.hpp"

namespace regbench::networks {

std::int64_t CostKey(const nlohmann::json& c, const char* key) {
    if (!c.contains(key)) {
        throw std::invalid_argument(std::string("forward cost: config has no \"") + key +
                                    "\": " + c.dump());
    }
    return c.at(key).get<std::int64_t>();
}

void AddMacs(ForwardCost& cost, const std::string& part, std::int64_t macs) {
    cost.parts[part] += macs;
    cost.total += macs;
}

std::int64_t DgcnnMacs(std::int64_t n, std::int64_t k, std::int64_t d) {
    constexpr std::int64_t kEdgeMacs = 6 * 64 + 64 * 64 + 64 * 128 + 128 * 256;  // 45,440 an edge
    return n * k * kEdgeMacs + n * 512 * d + 3 * n * n;
}

ForwardCost ComputeForwardCost(const nlohmann::json& config, std::int64_t source_points,
                               std::int64_t target_points) {
    if (source_points < 1 || target_points < 1) {
        throw std::invalid_argument("forward cost: point counts must be positive, got " +
                                    std::to_string(source_points) + " and " +
                                    std::to_string(target_points));
    }
    // A zoo config carries its training recipe under "train": not a network key, no cost.
    nlohmann::json net = config;
    if (net.is_object()) net.erase("train");
    return FamilyOfConfig(net).forward_cost(net, source_points, target_points);
}

ForwardCost CostOfParts(const std::map<std::string, std::int64_t>& parts) {
    ForwardCost cost;
    for (const auto& [part, macs] : parts) {
        if (part != "total") AddMacs(cost, part, macs);
    }
    return cost;
}

}  // namespace regbench::networks
