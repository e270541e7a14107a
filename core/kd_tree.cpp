#include "core/kd_tree.hpp"

#include <limits>

#include "core/nanoflann_adaptor.hpp"

namespace regbench {

struct KdTree::Impl {
    CloudAdaptor adaptor;
    CloudKdTree tree;
    Impl(const PointCloud& p, int leaf)
        : adaptor{p},
          tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(static_cast<size_t>(leaf))) {
        if (p.rows() > 0) tree.buildIndex();
    }
};

KdTree::KdTree(const PointCloud& points, int leaf_size)
    : points_(points), impl_(std::make_unique<Impl>(points, leaf_size)) {}

KdTree::~KdTree() = default;

std::pair<Eigen::Index, double> KdTree::Nearest(const Eigen::Vector3d& query) const {
    if (points_.rows() == 0) return {-1, std::numeric_limits<double>::infinity()};
    size_t index = 0;
    double sq = 0.0;
    nanoflann::KNNResultSet<double, size_t> result(1);
    result.init(&index, &sq);
    impl_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
    return {static_cast<Eigen::Index>(index), sq};
}

void KdTree::Knn(const Eigen::Vector3d& query, int k, std::vector<Eigen::Index>& indices,
                 std::vector<double>& sq_distances) const {
    indices.clear();
    sq_distances.clear();
    const size_t kk =
        std::min(static_cast<size_t>(std::max(k, 0)), static_cast<size_t>(points_.rows()));
    if (kk == 0) return;
    std::vector<size_t> idx(kk);
    sq_distances.resize(kk);
    nanoflann::KNNResultSet<double, size_t> result(kk);
    result.init(idx.data(), sq_distances.data());
    impl_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
    const size_t found = result.size();
    idx.resize(found);
    sq_distances.resize(found);
    indices.assign(idx.begin(), idx.end());
}

void KdTree::Radius(const Eigen::Vector3d& query, double radius,
                    std::vector<std::pair<Eigen::Index, double>>& index_sq_distance) const {
    index_sq_distance.clear();
    if (points_.rows() == 0) return;
    std::vector<std::pair<size_t, double>> matches;
    nanoflann::SearchParams params;
    params.sorted = true;
    impl_->tree.radiusSearch(query.data(), radius * radius, matches, params);
    index_sq_distance.reserve(matches.size());
    for (const auto& m : matches) {
        index_sq_distance.emplace_back(static_cast<Eigen::Index>(m.first), m.second);
    }
}

Eigen::VectorXd NearestDistances(const KdTree& tree, const PointCloud& queries) {
    Eigen::VectorXd out(queries.rows());
    for (Eigen::Index i = 0; i < queries.rows(); ++i) {
        out[i] = std::sqrt(tree.Nearest(queries.row(i).transpose()).second);
    }
    return out;
}

}  // namespace regbench
