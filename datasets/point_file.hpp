#pragma once
// Point cloud files: PLY and PCD (through Open3D) and plain-text XYZ.
#include <string>

#include "core/point_cloud.hpp"

namespace regbench {

/// What a PLY / PCD reader does with points that have a NaN or Inf coordinate (organized PCD
/// scans mark missing depth so): drop them and warn on stderr with their count and the file
/// (the default), or refuse the file naming it and the count. XYZ files always refuse such a
/// line, naming file:line.
enum class NonFinitePoints { kDrop, kRefuse };

/// Reads the points of a .ply, .pcd or .xyz/.xyzn/.txt file (extension decides; case-insensitive).
/// XYZ: one point per line, "x y z" optionally followed by more numbers (the next three are
/// read as a normal when every line has six or more); blank lines and '#' comments skipped;
/// any other line is rejected with file:line. When `normals` is not null it receives the
/// file's normals, or an empty matrix when it has none. Throws std::runtime_error naming the
/// path on a missing, empty, truncated or corrupt file.
PointCloud ReadPointFile(const std::string& path, Normals* normals = nullptr,
                         NonFinitePoints non_finite = NonFinitePoints::kDrop);

/// Points of a PLY / PCD / XYZ file, or the vertices of an OFF mesh (extension decides; case-
/// insensitive). Throws naming the path. What `regbench align` reads.
PointCloud ReadCloudFile(const std::string& path,
                         NonFinitePoints non_finite = NonFinitePoints::kDrop);

/// PLY / PCD through Open3D (point_file_open3d.cpp); used by ReadPointFile.
PointCloud ReadPointFileOpen3D(const std::string& path, Normals* normals,
                               NonFinitePoints non_finite = NonFinitePoints::kDrop);

}  // namespace regbench
