#pragma once
// OFF mesh files (ModelNet40, the CGAL corpus, indoor scenes).
#include <string>

#include "protocols/mesh.hpp"

namespace regbench {

/// Reads an OFF / COFF / NOFF file, tolerating ModelNet40's malformed header ("OFF490 ...") and
/// polygonal faces (fanned into triangles). Throws std::runtime_error naming the path on a
/// missing, truncated or corrupt file.
Mesh ReadOff(const std::string& path);

}  // namespace regbench
