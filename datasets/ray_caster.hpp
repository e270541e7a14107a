#pragma once
// First-hit ray casting against a triangle mesh (CGAL AABB tree, double precision). CGAL lives
// only in ray_caster.cpp; this header exposes Eigen types.
//
// Why CGAL and not Open3D's t::geometry::RaycastingScene: Debian's Open3D 0.16 build returns
// t_hit = inf for rays that plainly hit a mesh (a unit box hit head-on, a 20 m quad at z = 2),
// while its ComputeDistance works; CGAL's AABB_tree::first_intersection is exact-predicate,
// double precision and single-threaded per query, so depths are bitwise reproducible.
#include <Eigen/Core>
#include <memory>

#include "protocols/mesh.hpp"

namespace regbench {

/// Result of one ray query.
struct RayHit {
    bool hit = false;                                  ///< false: the ray leaves the scene
    double distance = 0.0;                             ///< along the unit direction [m]
    Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< the hit point
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< unit normal of the hit triangle
                                                       ///< (sign as the face winding gives it)
    Eigen::Index face = -1;                            ///< index of the hit triangle in the mesh
};

/// Thread-safety: construction builds the tree; CastRay is const and may run concurrently.
class RayCaster {
public:
    /// Builds the AABB tree over `mesh`'s triangles (degenerate triangles are skipped).
    /// Throws std::invalid_argument when the mesh has no non-degenerate triangle or a face
    /// indexes a missing vertex.
    explicit RayCaster(const Mesh& mesh);
    ~RayCaster();
    RayCaster(const RayCaster&) = delete;
    RayCaster& operator=(const RayCaster&) = delete;

    /// Closest intersection of the ray origin + s * direction, s >= 0 (direction need not be
    /// unit; the distance is reported along the normalised direction).
    RayHit CastRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;

    Eigen::Index num_triangles() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace regbench
