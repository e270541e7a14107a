#pragma once
// Glue between datasets (datasets/dataset.hpp) and pair protocols: records -> ShapeSources.
#include <vector>

#include "datasets/dataset.hpp"
#include "protocols/generate.hpp"
#include "protocols/shape_source.hpp"

namespace regbench {

/// Every record of `dataset`, in dataset order: mesh records become mesh sources (sampled on
/// the surface), point records point sources (resampled), records with a stored target and
/// transform stored-pair sources (ShapeSource::FromStoredPair). Each record is read once.
std::vector<ShapeSource> LoadShapeSources(const Dataset& dataset);

/// A ShapeLoader that opens (name_or_path, split) with `options` and loads every record.
ShapeLoader DatasetShapeLoader(const DatasetOptions& options);

}  // namespace regbench
