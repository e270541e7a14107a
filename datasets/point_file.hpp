#pragma once
// Point cloud files: PLY and PCD (through Open3D) and plain-text XYZ.
#include <string>

#include "core/point_cloud.hpp"

namespace regbench {

/// Reads the points of a .ply, .pcd or .xyz/.xyzn/.txt file (extension decides; case-insensitive).
/// XYZ: one point per line, "x y z" optionally followed by more numbers (the next three are
/// read as a normal when every line has six or more); blank lines and '#' comments skipped;
/// any other line is rejected with file:line. When `normals` is not null it receives the
/// file's normals, or an empty matrix when it has none. Throws std::runtime_error naming the
/// path on a missing, empty, truncated or corrupt file.
PointCloud ReadPointFile(const std::string& path, Normals* normals = nullptr);

/// Points of a PLY / PCD / XYZ file, or the vertices of an OFF mesh (extension decides; case-
/// insensitive). Throws naming the path. What `regbench align` reads.
PointCloud ReadCloudFile(const std::string& path);

/// PLY / PCD through Open3D (point_file_open3d.cpp); used by ReadPointFile.
PointCloud ReadPointFileOpen3D(const std::string& path, Normals* normals);

}  // namespace regbench
