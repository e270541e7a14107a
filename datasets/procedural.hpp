#pragma once
// Procedural shape corpus: seeded closed triangle meshes in ten categories (docs/datasets.md).
// It complements the ~40 embedded CGAL meshes, which are too few to train learned methods on.
#include <cstdint>
#include <string>
#include <vector>

#include "protocols/mesh.hpp"

namespace regbench {

/// The procedural categories in label order (alphabetical): bottle, chair, dumbbell, gear,
/// lamp, mushroom, superellipsoid, supertoroid, table, torus_knot.
const std::vector<std::string>& ProceduralCategories();

/// Shape `index` of category `label` (index into ProceduralCategories()). The mesh depends only
/// on (seed, label, index), is made of closed surfaces (parts of an assembly may intersect),
/// and lies roughly within [-1.5, 1.5]^3, not normalised. Throws std::invalid_argument on a
/// bad label.
Mesh MakeProceduralShape(int label, std::uint64_t seed, std::uint64_t index);

}  // namespace regbench
