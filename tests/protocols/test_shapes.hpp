#pragma once
// Small in-test shapes so protocol tests need no data files.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "core/math_constants.hpp"
#include "protocols/shape_source.hpp"

namespace regbench::test {

/// Ellipsoid with semi-axes (a, b, c) as a UV-sphere triangle mesh (inside the unit sphere).
inline Mesh EllipsoidMesh(double a, double b, double c, int stacks = 24, int slices = 48) {
    Mesh mesh;
    const int nv = (stacks + 1) * slices;
    mesh.vertices.resize(nv, 3);
    for (int i = 0; i <= stacks; ++i) {
        const double theta = kPi * i / stacks;
        for (int j = 0; j < slices; ++j) {
            const double phi = 2.0 * kPi * j / slices;
            mesh.vertices.row(i * slices + j) << a * std::sin(theta) * std::cos(phi),
                b * std::sin(theta) * std::sin(phi), c * std::cos(theta);
        }
    }
    std::vector<int> f;
    for (int i = 0; i < stacks; ++i) {
        for (int j = 0; j < slices; ++j) {
            const int v00 = i * slices + j, v01 = i * slices + (j + 1) % slices;
            const int v10 = v00 + slices, v11 = v01 + slices;
            f.insert(f.end(), {v00, v10, v11, v00, v11, v01});
        }
    }
    mesh.faces.resize(static_cast<Eigen::Index>(f.size() / 3), 3);
    for (std::size_t k = 0; k < f.size(); ++k) mesh.faces.data()[k] = f[k];
    return mesh;
}

/// Two mesh shapes and one point-cloud shape.
inline std::vector<ShapeSource> TestShapes() {
    std::vector<ShapeSource> shapes;
    shapes.push_back(ShapeSource::FromMesh(EllipsoidMesh(1.0, 0.6, 0.4), "ellipsoid", "blob"));
    shapes.push_back(ShapeSource::FromMesh(EllipsoidMesh(0.5, 0.9, 0.3), "ellipsoid2", "blob"));
    std::mt19937_64 rng(7);
    shapes.push_back(ShapeSource::FromPoints(shapes[0].Sample(3000, rng), "cloud", "scan"));
    return shapes;
}

}  // namespace regbench::test
