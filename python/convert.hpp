#pragma once
// Conversions between the C++ core's types and Python's: JSON values, point clouds and 4x4
// transforms. Input checks raise ValueError with the core's own messages (ValidateCloud).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>
#include <string>

#include "core/point_cloud.hpp"

namespace regbench::python {

namespace py = pybind11;

/// A JSON value as Python objects (dict, list, str, int, float, bool, None).
py::object JsonToPy(const nlohmann::json& j);

/// A Python value (dict with str keys, list, tuple, str, int, float, bool, None, NumPy scalars
/// and arrays) as JSON; anything else raises TypeError naming `what`. `enclosing` is how many
/// JSON containers will hold the value in its result row: a dict or list nesting deeper than
/// kMaxJsonDepth levels in all raises ValueError, as no reader would take the row back (a
/// callable's extras 100 levels deep were written, then refused on read-back; issue 44).
nlohmann::json PyToJson(py::handle value, const std::string& what, int enclosing = 0);

/// A method's parameters: None is {}, otherwise a dict (ValueError naming `what` if not, or
/// naming the key of a NaN or infinite number, which a row's JSON cannot record).
nlohmann::json ParamsToJson(py::handle params, const std::string& what);

/// An (N, 3) floating-point array (any array-like NumPy accepts) as a point cloud, copied.
/// Wrong shape, a non-float dtype, too few points or NaN/Inf raise ValueError naming `which`.
PointCloud CloudFromPy(py::handle value, const std::string& which);

/// A (4, 4) array-like of a floating-point or integer dtype as a transform; wrong shape, another
/// dtype (bool, complex, object) or non-finite entries raise ValueError naming `which`.
Transform TransformFromPy(py::handle value, const std::string& which);

/// A fresh, writable (N, 3) float64 copy of a cloud.
py::array_t<double> CloudToPy(const PointCloud& cloud);

/// A fresh (4, 4) float64 copy of a transform.
py::array_t<double> TransformToPy(const Transform& T);

/// An (N, 3) float64 view of `cloud`, kept alive by `owner` (no copy). Writable, because
/// libraries refuse read-only arrays (Open3D's Vector3dVector): writes change what this object
/// returns afterwards, never the file.
py::array CloudView(const PointCloud& cloud, py::handle owner);

}  // namespace regbench::python
