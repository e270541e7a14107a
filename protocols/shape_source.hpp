#pragma once
// Where a pair protocol draws its points from: a mesh surface or a fixed point cloud.
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "protocols/mesh.hpp"

namespace regbench {

/// One shape a protocol can sample: either a triangle mesh (already normalised; sampled
/// uniformly on its surface) or a point cloud (ModelNet40 HDF5 shapes, indoor scans; resampled
/// without replacement). Built once per shape and shared by every pair, so meshes are read and
/// their cumulative area tables computed once, not per pair. Immutable after construction:
/// Sample() may run concurrently with its own rng per thread.
class ShapeSource {
public:
    /// Mesh source. Throws std::invalid_argument naming `name` when the mesh has no face of
    /// positive area or a face index out of range.
    static ShapeSource FromMesh(Mesh mesh, std::string name, std::string category);
    /// Point-cloud source. Throws std::invalid_argument naming `name` when `points` is empty
    /// or holds a non-finite coordinate.
    static ShapeSource FromPoints(PointCloud points, std::string name, std::string category);
    /// A pair stored in a dataset file (DeepGMR-style test files such as ICL-NUIM's
    /// test/icl_nuim.h5: `source`, `target` and the transform mapping source onto target).
    /// Sample() resamples `source` as FromPoints does; the `stored` pairing uses the three as
    /// stored. The rotation block is re-orthonormalised (float32 files store it to ~1e-7).
    /// Throws std::invalid_argument naming `name` when a cloud is empty or non-finite or the
    /// transform is not rigid within 1e-4 (last row, R^T R = I, det R = +1).
    static ShapeSource FromStoredPair(PointCloud source, PointCloud target,
                                      const Transform& target_from_source, std::string name,
                                      std::string category);

    /// n points. Mesh: area-weighted triangle choice (binary search in the cumulative area
    /// table), uniform barycentric coordinates (r1 = sqrt(u1): Osada et al. 2002, eq. 1).
    /// Point cloud: n distinct points in random order (partial Fisher-Yates); throws
    /// std::invalid_argument naming the shape when it holds fewer than n points.
    /// Uses only `rng` (portable draws from core/rng.hpp).
    PointCloud Sample(Eigen::Index n, std::mt19937_64& rng) const;

    const std::string& name() const { return name_; }
    const std::string& category() const { return category_; }
    bool is_mesh() const { return mesh_ != nullptr; }
    /// The mesh of a mesh source, null otherwise; with name() and category() all FromMesh needs
    /// to rebuild the source (training bundles, experiments/training_bundle.hpp).
    const Mesh* mesh() const { return mesh_.get(); }
    /// The points of a point or stored-pair source (its source cloud), null for a mesh source.
    const PointCloud* points() const { return points_.get(); }
    /// Number of points (point source) or triangles (mesh source).
    Eigen::Index size() const;
    /// True for FromStoredPair sources.
    bool has_stored_pair() const { return stored_target_ != nullptr; }
    /// The stored source cloud, target cloud and source-to-target transform; throw
    /// std::logic_error naming the shape when has_stored_pair() is false.
    const PointCloud& stored_source() const;
    const PointCloud& stored_target() const;
    const Transform& stored_transform() const;

private:
    ShapeSource() = default;
    PointCloud SampleMesh(Eigen::Index n, std::mt19937_64& rng) const;
    PointCloud SamplePoints(Eigen::Index n, std::mt19937_64& rng) const;

    std::string name_;
    std::string category_;
    std::shared_ptr<const Mesh> mesh_;
    std::shared_ptr<const std::vector<double>> cumulative_area_;  ///< running sum of face areas
    std::shared_ptr<const PointCloud> points_;
    std::shared_ptr<const PointCloud> stored_target_;  ///< FromStoredPair only
    Transform stored_transform_ = Transform::Identity();
};

}  // namespace regbench
