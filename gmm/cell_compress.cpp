#include "gmm/cell_compress.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

namespace regbench {

CellCompressed CompressToCells(const PointCloud& points, const Eigen::VectorXd* weights,
                               double cell) {
    const Eigen::Index n = points.rows();
    if (n == 0) throw std::invalid_argument("CompressToCells: cloud is empty");
    if (!(cell > 0.0) || !std::isfinite(cell)) {
        throw std::invalid_argument("CompressToCells: cell edge must be positive and finite");
    }
    if (weights != nullptr && weights->size() != n) {
        throw std::invalid_argument("CompressToCells: weights and points differ in length");
    }
    // 21 bits per axis in one 64-bit key, relative to the cloud's minimum corner.
    constexpr double kMaxCellsPerAxis = 1 << 20;
    const Eigen::RowVector3d lo = (points.colwise().minCoeff().array() / cell).floor().matrix();
    const Eigen::RowVector3d hi = (points.colwise().maxCoeff().array() / cell).floor().matrix();
    if ((hi - lo).maxCoeff() >= kMaxCellsPerAxis) {
        throw std::invalid_argument("CompressToCells: cell edge " + std::to_string(cell) +
                                    " is too small for the cloud's extent");
    }
    std::vector<std::pair<std::uint64_t, Eigen::Index>> keyed(static_cast<size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) {
        std::uint64_t key = 0;
        for (int d = 0; d < 3; ++d) {
            const auto c = static_cast<std::uint64_t>(std::floor(points(i, d) / cell) - lo[d]);
            key = (key << 21) | c;
        }
        keyed[static_cast<size_t>(i)] = {key, i};
    }
    std::sort(keyed.begin(), keyed.end());

    CellCompressed out;
    std::vector<Eigen::Vector3d> sums;
    std::vector<Eigen::Vector3d> plain;
    std::vector<double> w_sums;
    std::vector<Eigen::Index> counts;
    for (size_t k = 0; k < keyed.size(); ++k) {
        if (k == 0 || keyed[k].first != keyed[k - 1].first) {
            sums.emplace_back(Eigen::Vector3d::Zero());
            plain.emplace_back(Eigen::Vector3d::Zero());
            w_sums.push_back(0.0);
            counts.push_back(0);
        }
        const Eigen::Index i = keyed[k].second;
        const double w = weights ? (*weights)[i] : 1.0;
        const Eigen::Vector3d p = points.row(i).transpose();
        sums.back() += w * p;
        plain.back() += p;
        w_sums.back() += w;
        ++counts.back();
    }
    const auto c = static_cast<Eigen::Index>(sums.size());
    out.centroids.resize(c, 3);
    out.weights.resize(c);
    for (Eigen::Index k = 0; k < c; ++k) {
        const auto ku = static_cast<size_t>(k);
        out.weights[k] = w_sums[ku];
        out.centroids.row(k) =
            (w_sums[ku] > 0.0 ? Eigen::Vector3d(sums[ku] / w_sums[ku])
                              : Eigen::Vector3d(plain[ku] / static_cast<double>(counts[ku])))
                .transpose();
    }
    return out;
}

}  // namespace regbench
