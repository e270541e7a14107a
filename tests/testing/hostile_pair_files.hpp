#pragma once
// Hostile pair files for the validation tests, written with the HDF5 C API (no h5py needed):
// a valid two-pair file is written by WritePairFile, then one field is corrupted in place.
#include <hdf5.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "protocols/pair_file.hpp"
#include "tests/testing/synthetic.hpp"

namespace regbench::testing {

/// A hostile file: its name, what is wrong, and a word the reader's error must contain.
struct HostileCase {
    std::string name;
    std::string expect;  ///< substring of the error message
    std::function<void(hid_t file)> corrupt;
};

inline void SetDoubleAttr(hid_t obj, const char* name, double v) {
    if (H5Aexists(obj, name) > 0) H5Adelete(obj, name);
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate2(obj, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(attr, H5T_NATIVE_DOUBLE, &v);
    H5Aclose(attr);
    H5Sclose(space);
}

/// Replaces attribute `name` of `obj` by the fixed-length string `v` (any bytes).
inline void SetStringAttr(hid_t obj, const char* name, const std::string& v) {
    if (H5Aexists(obj, name) > 0) H5Adelete(obj, name);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, v.size());
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(attr, type, v.data());
    H5Aclose(attr);
    H5Sclose(space);
    H5Tclose(type);
}

/// Sets a string attribute of pair 1's group.
inline std::function<void(hid_t)> SetPairString(const char* name, std::string v) {
    return [name, v](hid_t f) {
        const hid_t g = H5Gopen2(f, "/pairs/000001", H5P_DEFAULT);
        SetStringAttr(g, name, v);
        H5Gclose(g);
    };
}

/// Replaces dataset `path` by one of shape `dims`; writes `values` unless empty (then the
/// dataset has no storage at all: a header that declares data the file does not hold).
inline void ReplaceDataset(hid_t file, const std::string& path, std::vector<hsize_t> dims,
                           const std::vector<double>& values) {
    H5Ldelete(file, path.c_str(), H5P_DEFAULT);
    const hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
    const hid_t ds = H5Dcreate2(file, path.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT,
                                H5P_DEFAULT);
    if (!values.empty())
        H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
    H5Dclose(ds);
    H5Sclose(space);
}

/// T_gt of pair 1 replaced by the row-major 4x4 `m`.
inline std::function<void(hid_t)> SetTgt(std::vector<double> m) {
    return [m](hid_t f) { ReplaceDataset(f, "/pairs/000001/T_gt", {4, 4}, m); };
}

/// Pair 1's source with one coordinate set to `v` (20 points, as TwoPairFile writes).
inline std::function<void(hid_t)> SetSourceValue(double v) {
    return [v](hid_t f) {
        std::vector<double> pts(60, 0.1);
        pts[31] = v;
        ReplaceDataset(f, "/pairs/000001/source", {20, 3}, pts);
    };
}

inline std::vector<HostileCase> HostileCases() {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {
        {"version99", "format_version", [](hid_t f) { SetDoubleAttr(f, "format_version", 99); }},
        {"num_pairs_1e30", "num_pairs", [](hid_t f) { SetDoubleAttr(f, "num_pairs", 1e30); }},
        {"num_pairs_2_5", "num_pairs", [](hid_t f) { SetDoubleAttr(f, "num_pairs", 2.5); }},
        {"num_pairs_3", "num_pairs", [](hid_t f) { SetDoubleAttr(f, "num_pairs", 3); }},
        {"num_pairs_nan", "num_pairs", [nan](hid_t f) { SetDoubleAttr(f, "num_pairs", nan); }},
        {"tgt_scaled", "orthonormal", SetTgt({2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1})},
        {"tgt_reflected", "reflection", SetTgt({-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1})},
        {"tgt_zero", "last row", SetTgt(std::vector<double>(16, 0.0))},
        {"tgt_nan", "non-finite", SetTgt({nan, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1})},
        {"tgt_bad_last_row", "last row",
         SetTgt({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0.5, 0, 0, 1})},
        {"source_nan", "non-finite", SetSourceValue(nan)},
        {"source_1e300", "float", SetSourceValue(1e300)},
        {"source_empty", "empty",
         [](hid_t f) {
             ReplaceDataset(f, "/pairs/000001/source", {0, 3}, {});
         }},
        {"source_1e8_points", "declares",
         [](hid_t f) {
             ReplaceDataset(f, "/pairs/000001/source", {100000000, 3}, {});
         }},
        {"source_2e9_points", "declares",
         [](hid_t f) {
             ReplaceDataset(f, "/pairs/000001/source", {2000000000, 3}, {});
         }},
        {"source_rank1", "rank",
         [](hid_t f) {
             ReplaceDataset(f, "/pairs/000001/source", {60}, std::vector<double>(60, 0.1));
         }},
        {"missing_group", "num_pairs", [](hid_t f) { H5Ldelete(f, "/pairs/000001", H5P_DEFAULT); }},
        // Issue 27: these ended in a bare [json.exception.type_error.316/302] naming nothing.
        {"shape_not_utf8", "attribute 'shape' is not valid UTF-8",
         SetPairString("shape",
                       "a\xFF"
                       "b")},
        {"category_not_utf8", "attribute 'category' is not valid UTF-8",
         SetPairString("category", "\xC3")},
        {"provenance_not_utf8", "attribute 'provenance' is not valid UTF-8",
         [](hid_t f) { SetStringAttr(f, "provenance", "{\"protocol\": \"\xFF\"}"); }},
        {"provenance_mistyped", "provenance key 'dataset' must be a string",
         [](hid_t f) { SetStringAttr(f, "provenance", R"({"protocol": "test", "dataset": 5})"); }},
        {"provenance_deep", "JSON nested deeper than 64 levels",
         [](hid_t f) {
             SetStringAttr(f, "provenance", std::string(100, '[') + std::string(100, ']'));
         }},
        // Issue 44: links and storage outside the file. An external link to a FIFO hung `run`
        // and `inspect` for ever; external storage read any local file as coordinates.
        {"source_external_link", "external link",
         [](hid_t f) {
             H5Ldelete(f, "/pairs/000001/source", H5P_DEFAULT);
             H5Lcreate_external("/nonexistent/other.h5", "/x", f, "/pairs/000001/source",
                                H5P_DEFAULT, H5P_DEFAULT);
         }},
        {"pair_soft_link", "soft or user link",
         [](hid_t f) {
             H5Ldelete(f, "/pairs/000001", H5P_DEFAULT);
             H5Lcreate_soft("/pairs/000000", f, "/pairs/000001", H5P_DEFAULT, H5P_DEFAULT);
         }},
        {"source_external_storage", "external storage",
         [](hid_t f) {
             H5Ldelete(f, "/pairs/000001/source", H5P_DEFAULT);
             const hsize_t dims[2] = {20, 3};
             const hid_t space = H5Screate_simple(2, dims, nullptr);
             const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
             H5Pset_external(dcpl, "/dev/zero", 0, 20 * 3 * sizeof(double));
             const hid_t ds = H5Dcreate2(f, "/pairs/000001/source", H5T_IEEE_F64LE, space,
                                         H5P_DEFAULT, dcpl, H5P_DEFAULT);
             H5Dclose(ds);
             H5Pclose(dcpl);
             H5Sclose(space);
         }},
    };
}

/// Writes a valid two-pair file to `path`, then applies `c.corrupt` to it.
inline void WriteHostile(const std::string& path, const HostileCase& c) {
    PairSet set;
    set.provenance = {{"protocol", "test"}, {"seed", 5}};
    set.pairs.push_back(SyntheticPair(20, 1, Transform::Identity()));
    set.pairs.push_back(SyntheticPair(20, 2, Transform::Identity()));
    WritePairFile(path, set);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    c.corrupt(file);
    H5Fclose(file);
}

}  // namespace regbench::testing
