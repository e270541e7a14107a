// CGAL translation unit: AABB tree over triangles, first_intersection per ray.
#include "datasets/ray_caster.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace regbench {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using Vector3 = Kernel::Vector_3;
using Ray3 = Kernel::Ray_3;
using Segment3 = Kernel::Segment_3;
using Triangle3 = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle3>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Traits = CGAL::AABB_traits<Kernel, Primitive>;
using Tree = CGAL::AABB_tree<Traits>;

Point3 ToPoint(const Eigen::Vector3d& p) { return Point3(p.x(), p.y(), p.z()); }
Eigen::Vector3d ToEigen(const Point3& p) { return Eigen::Vector3d(p.x(), p.y(), p.z()); }

}  // namespace

struct RayCaster::Impl {
    std::vector<Triangle3> triangles;
    std::vector<Eigen::Index> face_index;  // triangle -> face of the input mesh
    std::vector<Eigen::Vector3d> normals;  // unit, per triangle
    Tree tree;
};

RayCaster::RayCaster(const Mesh& mesh) : impl_(std::make_unique<Impl>()) {
    const Eigen::Index num_vertices = mesh.vertices.rows();
    impl_->triangles.reserve(static_cast<std::size_t>(mesh.faces.rows()));
    for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
        Eigen::Vector3d corner[3];
        for (int k = 0; k < 3; ++k) {
            const int v = mesh.faces(f, k);
            if (v < 0 || v >= num_vertices) {
                throw std::invalid_argument("RayCaster: face " + std::to_string(f) +
                                            " indexes missing vertex " + std::to_string(v));
            }
            corner[k] = mesh.vertices.row(v).transpose();
        }
        const Eigen::Vector3d cross = (corner[1] - corner[0]).cross(corner[2] - corner[0]);
        const double norm = cross.norm();
        if (!(norm > 0.0) || !std::isfinite(norm)) continue;  // degenerate: no surface to hit
        impl_->triangles.emplace_back(ToPoint(corner[0]), ToPoint(corner[1]), ToPoint(corner[2]));
        impl_->face_index.push_back(f);
        impl_->normals.push_back(cross / norm);
    }
    if (impl_->triangles.empty()) {
        throw std::invalid_argument("RayCaster: mesh has no non-degenerate triangle");
    }
    impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
    impl_->tree.build();
}

RayCaster::~RayCaster() = default;

Eigen::Index RayCaster::num_triangles() const {
    return static_cast<Eigen::Index>(impl_->triangles.size());
}

RayHit RayCaster::CastRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
    RayHit result;
    const double length = direction.norm();
    if (!(length > 0.0)) return result;
    const Eigen::Vector3d unit = direction / length;
    const Ray3 ray(ToPoint(origin), Vector3(unit.x(), unit.y(), unit.z()));
    const auto intersection = impl_->tree.first_intersection(ray);
    if (!intersection) return result;

    // A ray in the plane of a triangle meets it in a segment: its near end is the first hit.
    Eigen::Vector3d point;
    if (const Point3* p = boost::get<Point3>(&intersection->first)) {
        point = ToEigen(*p);
    } else if (const Segment3* s = boost::get<Segment3>(&intersection->first)) {
        const Eigen::Vector3d a = ToEigen(s->source());
        const Eigen::Vector3d b = ToEigen(s->target());
        point = (a - origin).dot(unit) <= (b - origin).dot(unit) ? a : b;
    } else {
        return result;
    }
    const auto triangle =
        static_cast<std::size_t>(intersection->second - impl_->triangles.cbegin());
    result.hit = true;
    result.point = point;
    result.distance = std::max((point - origin).dot(unit), 0.0);
    result.normal = impl_->normals[triangle];
    result.face = impl_->face_index[triangle];
    return result;
}

}  // namespace regbench
