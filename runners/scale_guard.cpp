#include "runners/scale_guard.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "runners/registry.hpp"

namespace regbench {
namespace {

std::size_t Points(const PointCloud& c) { return static_cast<std::size_t>(c.rows()); }

/// Evenly spaced rows floor(i * n / k) of a cloud and its labels.
void Stride(const PointCloud& in, const Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1>& labels,
            std::size_t k, PointCloud* out,
            Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1>* out_labels) {
    const std::size_t n = Points(in);
    out->resize(static_cast<Eigen::Index>(k), 3);
    out_labels->resize(static_cast<Eigen::Index>(labels.size() == in.rows() ? k : 0));
    for (std::size_t i = 0; i < k; ++i) {
        const auto row = static_cast<Eigen::Index>(i * n / k);
        out->row(static_cast<Eigen::Index>(i)) = in.row(row);
        if (out_labels->size() > 0) (*out_labels)(static_cast<Eigen::Index>(i)) = labels(row);
    }
}

/// NeedsScaleGuard for clouds of these sizes.
bool QuadraticAbove(std::optional<CostClass> cost, std::size_t source_points,
                    std::size_t target_points, std::size_t max_points) {
    return max_points > 0 && cost == CostClass::kQuadratic &&
           std::max(source_points, target_points) > max_points;
}

}  // namespace

std::optional<CostClass> GuardedCost(const MethodSpec& method, const RunOptions& options) {
    const auto external = options.external_methods.find(method.name);
    if (external == options.external_methods.end()) return MethodCost(method.name, method.params);
    if (!external->second.cost) return std::nullopt;
    return external->second.cost(method.params);
}

bool NeedsScaleGuard(std::optional<CostClass> cost, const Pair& pair, std::size_t max_points) {
    return QuadraticAbove(cost, Points(pair.source), Points(pair.target), max_points);
}

void RequireCallScale(const MethodSpec& method, std::size_t source_points,
                      std::size_t target_points, std::size_t max_points) {
    if (!QuadraticAbove(MethodCost(method.name, method.params), source_points, target_points,
                        max_points)) {
        return;
    }
    const double nm = static_cast<double>(source_points) * static_cast<double>(target_points);
    char line[512];
    std::snprintf(line, sizeof(line),
                  "%s is O(N*M): source has %zu points, target %zu, above max_points %zu (%.3g "
                  "point pairs per iteration, %.3gx a 10,000-point pair, which takes CPD ~4.5 s "
                  "on one thread)",
                  method.name.c_str(), source_points, target_points, max_points, nm, nm / 1e8);
    throw std::invalid_argument(line);
}

std::string CheckScale(const PairSet& set, const std::vector<std::size_t>& indices,
                       const RunOptions& options) {
    const std::size_t max_points = options.max_points;
    const bool downsample = options.downsample;
    std::string report;
    for (const auto& spec : options.methods) {
        const std::optional<CostClass> cost = GuardedCost(spec, options);
        std::size_t affected = 0;
        double worst = 0;
        std::size_t worst_pair = 0;
        for (const std::size_t k : indices) {
            const Pair& p = set.pairs[k];
            if (!NeedsScaleGuard(cost, p, max_points)) continue;
            ++affected;
            const double nm = static_cast<double>(Points(p.source)) * Points(p.target);
            if (nm > worst) {
                worst = nm;
                worst_pair = k;
            }
        }
        if (affected == 0) continue;
        const Pair& w = set.pairs[worst_pair];
        char line[512];
        std::snprintf(
            line, sizeof(line),
            "%s (dense) is O(N*M): %zu pair(s) have a cloud above --max-points %zu; the largest, "
            "pair %zu, is %zu x %zu points = %.3g kernel evaluations per iteration "
            "(%.2gx a 10,000-point pair, which takes CPD ~4.5 s on one thread)",
            spec.name.c_str(), affected, max_points, worst_pair, Points(w.source), Points(w.target),
            worst, worst / 1e8);
        report += std::string(line) + "\n";
    }
    if (report.empty()) return report;
    if (!downsample) {
        throw std::runtime_error(
            "run: refusing O(N*M) methods on large clouds:\n" + report +
            "pass --downsample to run them on clouds reduced to --max-points by the stride rule "
            "(recorded in each row), raise --max-points, or --max-points 0 to run as is");
    }
    return report +
           "these calls run on clouds downsampled to --max-points (stride rule; each "
           "row records it under \"downsampled\")\n";
}

Pair DownsampleByStride(const Pair& pair, std::size_t max_points, nlohmann::json* note) {
    Pair out = pair;
    const std::size_t n = Points(pair.source), m = Points(pair.target);
    if (n > max_points) {
        Stride(pair.source, pair.source_overlap, max_points, &out.source, &out.source_overlap);
    }
    if (m > max_points) {
        Stride(pair.target, pair.target_overlap, max_points, &out.target, &out.target_overlap);
    }
    if (note != nullptr) {
        *note = {{"rule", "stride"},
                 {"max_points", max_points},
                 {"source_points", {n, Points(out.source)}},
                 {"target_points", {m, Points(out.target)}}};
    }
    return out;
}

}  // namespace regbench
