#include "python/convert.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "core/json_limits.hpp"
#include "core/registration.hpp"

namespace regbench::python {

py::object JsonToPy(const nlohmann::json& j) {
    switch (j.type()) {
        case nlohmann::json::value_t::boolean:
            return py::bool_(j.get<bool>());
        case nlohmann::json::value_t::number_integer:
            return py::int_(j.get<std::int64_t>());
        case nlohmann::json::value_t::number_unsigned:
            return py::int_(j.get<std::uint64_t>());
        case nlohmann::json::value_t::number_float:
            return py::float_(j.get<double>());
        case nlohmann::json::value_t::string:
            return py::str(j.get_ref<const std::string&>());
        case nlohmann::json::value_t::array: {
            py::list out;
            for (const auto& v : j) out.append(JsonToPy(v));
            return std::move(out);
        }
        case nlohmann::json::value_t::object: {
            py::dict out;
            for (const auto& item : j.items()) out[py::str(item.key())] = JsonToPy(item.value());
            return std::move(out);
        }
        default:
            return py::none();
    }
}

nlohmann::json PyToJson(py::handle value, const std::string& what, int enclosing) {
    const bool container = py::isinstance<py::dict>(value) || py::isinstance<py::list>(value) ||
                           py::isinstance<py::tuple>(value) || py::isinstance<py::array>(value);
    if (container && enclosing + 1 > kMaxJsonDepth) {
        throw py::value_error(what + ": nested deeper than " + std::to_string(kMaxJsonDepth) +
                              " levels in its result row (no reader would take the row back)");
    }
    if (value.is_none()) return nullptr;
    if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
    if (py::isinstance<py::int_>(value)) {
        try {
            return value.cast<std::int64_t>();
        } catch (const py::cast_error&) {
            try {
                return value.cast<std::uint64_t>();
            } catch (const py::cast_error&) {
                throw py::value_error(what + ": integer " + py::str(value).cast<std::string>() +
                                      " does not fit 64 bits");
            }
        }
    }
    if (py::isinstance<py::float_>(value)) return value.cast<double>();
    if (py::isinstance<py::str>(value)) return value.cast<std::string>();
    if (py::isinstance<py::array>(value)) {
        return PyToJson(value.attr("tolist")(), what, enclosing);
    }
    // NumPy scalars (numpy.float32, numpy.int64, numpy.bool_): their Python value.
    if (py::hasattr(value, "dtype") && py::hasattr(value, "item")) {
        return PyToJson(value.attr("item")(), what, enclosing);
    }
    if (py::isinstance<py::dict>(value)) {
        nlohmann::json out = nlohmann::json::object();
        for (const auto& item : value.cast<py::dict>()) {
            if (!py::isinstance<py::str>(item.first)) {
                throw py::type_error(what + ": dict keys must be str, got " +
                                     py::repr(item.first).cast<std::string>());
            }
            const std::string key = item.first.cast<std::string>();
            out[key] = PyToJson(item.second, what + "." + key, enclosing + 1);
        }
        return out;
    }
    if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
        nlohmann::json out = nlohmann::json::array();
        for (const auto& v : value) out.push_back(PyToJson(v, what, enclosing + 1));
        return out;
    }
    throw py::type_error(what + ": cannot store a value of type " +
                         py::str(value.get_type().attr("__name__")).cast<std::string>() +
                         " as JSON (use dict, list, str, int, float, bool or None)");
}

namespace {

/// Parameters are recorded in every result row as JSON, which has no NaN or infinity (a row
/// would hold null, and resuming would find other parameters): refused by name, as the CLI's
/// JSON parser refuses them.
void RefuseNonFinite(const nlohmann::json& j, const std::string& what) {
    if (j.is_number_float() && !std::isfinite(j.get<double>())) {
        throw py::value_error(what + " must be finite (JSON has no NaN or infinity), got " +
                              std::to_string(j.get<double>()));
    }
    if (j.is_object()) {
        for (const auto& item : j.items()) RefuseNonFinite(item.value(), what + "." + item.key());
    } else if (j.is_array()) {
        for (const auto& v : j) RefuseNonFinite(v, what);
    }
}

}  // namespace

nlohmann::json ParamsToJson(py::handle params, const std::string& what) {
    if (params.is_none()) return nlohmann::json::object();
    if (!py::isinstance<py::dict>(params)) {
        throw py::value_error(what + " must be a dict (or None), got " +
                              py::str(params.get_type().attr("__name__")).cast<std::string>());
    }
    nlohmann::json j = PyToJson(params, what, /*enclosing=*/1);  // a row's "params"
    RefuseNonFinite(j, what);
    return j;
}

namespace {

std::string ShapeText(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) {
        s += (i ? ", " : "") + std::to_string(a.shape(i));
    }
    return s + (a.ndim() == 1 ? ",)" : ")");
}

/// `value` as a NumPy array of floating-point dtype (or integer too, when `integers`) and
/// `cols` columns (any rows when rows < 0), converted to float64.
py::array_t<double, py::array::c_style | py::array::forcecast> FloatMatrix(
    py::handle value, const std::string& which, py::ssize_t rows, py::ssize_t cols, bool integers) {
    const std::string expected =
        rows < 0 ? "(N, " + std::to_string(cols) + ")"
                 : "(" + std::to_string(rows) + ", " + std::to_string(cols) + ")";
    py::array a;
    try {
        a = py::array::ensure(value);
    } catch (const py::error_already_set&) {
    }
    if (!a) {
        throw py::value_error(which + " must be a NumPy array of shape " + expected + ", got " +
                              py::str(value.get_type().attr("__name__")).cast<std::string>());
    }
    const char kind = a.dtype().kind();
    if (integers && kind != 'f' && kind != 'i' && kind != 'u') {
        throw py::value_error(which + " must have a floating-point or integer dtype, got " +
                              py::str(a.dtype()).cast<std::string>());
    }
    if (!integers && kind != 'f') {
        throw py::value_error(which +
                              " must have a floating-point dtype (float32 or float64), got " +
                              py::str(a.dtype()).cast<std::string>());
    }
    if (a.ndim() != 2 || (rows >= 0 && a.shape(0) != rows) || a.shape(1) != cols) {
        throw py::value_error(which + " must have shape " + expected + ", got " + ShapeText(a));
    }
    return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
}

}  // namespace

PointCloud CloudFromPy(py::handle value, const std::string& which) {
    const auto a = FloatMatrix(value, which, -1, 3, /*integers=*/false);
    PointCloud cloud(a.shape(0), 3);
    if (a.size() > 0) std::memcpy(cloud.data(), a.data(), sizeof(double) * a.size());
    const std::string problem = ValidateCloud(cloud, which);
    if (!problem.empty()) throw py::value_error(problem);
    return cloud;
}

Transform TransformFromPy(py::handle value, const std::string& which) {
    // A 4x4 array-like: np.eye(4, dtype=int) and nested lists of ints are transforms too.
    const auto a = FloatMatrix(value, which, 4, 4, /*integers=*/true);
    Transform T;
    const auto r = a.unchecked<2>();
    for (int i = 0; i < 4; ++i) {
        for (int k = 0; k < 4; ++k) T(i, k) = r(i, k);
    }
    if (!T.allFinite()) throw py::value_error(which + " has non-finite (NaN or Inf) entries");
    return T;
}

py::array_t<double> CloudToPy(const PointCloud& cloud) {
    py::array_t<double> out({static_cast<py::ssize_t>(cloud.rows()), py::ssize_t{3}});
    if (cloud.size() > 0) {
        std::memcpy(out.mutable_data(), cloud.data(), sizeof(double) * cloud.size());
    }
    return out;
}

py::array_t<double> TransformToPy(const Transform& T) {
    py::array_t<double> out({py::ssize_t{4}, py::ssize_t{4}});
    auto w = out.mutable_unchecked<2>();
    for (int i = 0; i < 4; ++i) {
        for (int k = 0; k < 4; ++k) w(i, k) = T(i, k);
    }
    return out;
}

py::array CloudView(const PointCloud& cloud, py::handle owner) {
    // PointCloud is row-major N x 3 doubles: exactly NumPy's C-ordered (N, 3) float64.
    py::array view(
        py::dtype::of<double>(), {static_cast<py::ssize_t>(cloud.rows()), py::ssize_t{3}},
        {static_cast<py::ssize_t>(3 * sizeof(double)), static_cast<py::ssize_t>(sizeof(double))},
        cloud.data(), owner);
    return view;
}

}  // namespace regbench::python
