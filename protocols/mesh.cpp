#include "protocols/mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/rng.hpp"

namespace regbench {

Mesh NormalizeToUnitSphere(const Mesh& mesh) {
    if (mesh.vertices.rows() == 0) {
        throw std::invalid_argument("NormalizeToUnitSphere: mesh has no vertices");
    }
    const Eigen::RowVector3d lo = mesh.vertices.colwise().minCoeff();
    const Eigen::RowVector3d hi = mesh.vertices.colwise().maxCoeff();
    const Eigen::RowVector3d centre = 0.5 * (lo + hi);
    Mesh out = mesh;
    out.vertices.rowwise() -= centre;
    const double max_norm = out.vertices.rowwise().norm().maxCoeff();
    if (!(max_norm > 0.0) || !std::isfinite(max_norm)) {
        throw std::invalid_argument("NormalizeToUnitSphere: degenerate mesh (all vertices equal)");
    }
    out.vertices /= max_norm;
    return out;
}

namespace {

double TriangleArea(const Mesh& mesh, Eigen::Index f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0)).transpose();
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1)).transpose();
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2)).transpose();
    return 0.5 * (b - a).cross(c - a).norm();
}

void CheckFaces(const Mesh& mesh, const char* who) {
    const Eigen::Index nv = mesh.vertices.rows();
    if (mesh.faces.rows() > 0 && (mesh.faces.minCoeff() < 0 || mesh.faces.maxCoeff() >= nv)) {
        throw std::invalid_argument(std::string(who) + ": face index out of range");
    }
}

}  // namespace

double SurfaceArea(const Mesh& mesh) {
    CheckFaces(mesh, "SurfaceArea");
    double area = 0.0;
    for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) area += TriangleArea(mesh, f);
    return area;
}

PointCloud SampleSurface(const Mesh& mesh, Eigen::Index n, std::mt19937_64& rng) {
    if (n < 0) throw std::invalid_argument("SampleSurface: negative point count");
    CheckFaces(mesh, "SampleSurface");
    // Cumulative areas: triangle t is picked when u in [cum[t-1], cum[t]), so P(t) ~ area(t).
    std::vector<double> cumulative(static_cast<std::size_t>(mesh.faces.rows()));
    double total = 0.0;
    for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
        total += TriangleArea(mesh, f);
        cumulative[static_cast<std::size_t>(f)] = total;
    }
    if (!(total > 0.0) || !std::isfinite(total)) {
        throw std::invalid_argument("SampleSurface: mesh has no surface area");
    }
    PointCloud points(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        const double u = UniformReal(rng, 0.0, total);
        auto it = std::upper_bound(cumulative.begin(), cumulative.end(), u);
        // upper_bound never lands on a zero-area triangle; u can round up to `total`.
        if (it == cumulative.end()) --it;
        const Eigen::Index f = static_cast<Eigen::Index>(it - cumulative.begin());
        // Uniform barycentric (Osada et al. 2002): p = (1-sqrt r1) a + sqrt r1 (1-r2) b + sqrt r1
        // r2 c.
        const double s = std::sqrt(UniformReal(rng, 0.0, 1.0));
        const double r2 = UniformReal(rng, 0.0, 1.0);
        points.row(i) = (1.0 - s) * mesh.vertices.row(mesh.faces(f, 0)) +
                        s * (1.0 - r2) * mesh.vertices.row(mesh.faces(f, 1)) +
                        s * r2 * mesh.vertices.row(mesh.faces(f, 2));
    }
    return points;
}

}  // namespace regbench
