#pragma once
// Triangle meshes: normalising into the unit sphere, area-weighted surface sampling. Reading
// mesh files is datasets/off_reader.hpp.
#include <Eigen/Core>
#include <random>
#include <string>

#include "core/point_cloud.hpp"

namespace regbench {

struct Mesh {
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> vertices;
    Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> faces;  ///< triangles (polygons fanned)
};

/// Centres the mesh at its bounding-box centre and scales it so every vertex lies in the unit
/// sphere (max vertex norm = 1), as ModelNet40 preprocessing does.
Mesh NormalizeToUnitSphere(const Mesh& mesh);

/// n points uniformly on the surface: triangle chosen with probability proportional to area,
/// uniform barycentric coordinates (sqrt trick). Uses only `rng`.
PointCloud SampleSurface(const Mesh& mesh, Eigen::Index n, std::mt19937_64& rng);

/// Total surface area.
double SurfaceArea(const Mesh& mesh);

}  // namespace regbench
