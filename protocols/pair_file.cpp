#include "protocols/pair_file.hpp"

#include <hdf5.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "protocols/hdf5_handle.hpp"

namespace regbench {
namespace {

constexpr const char* kFormatName = "regbench-pairs";
constexpr int kFormatVersion = 1;

[[noreturn]] void Fail(const std::string& path, const std::string& what) {
    throw std::runtime_error(path + ": " + what);
}

using Handle = H5Handle;

std::string PairGroupName(std::size_t k) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "/pairs/%06zu", k);
    return buf;
}

/// Property lists without object timestamps, so identical content gives identical bytes.
Handle NoTimesGroupPlist() {
    Handle p(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
    H5Pset_obj_track_times(p.get(), false);
    return p;
}

void WriteStringAttr(const std::string& path, hid_t obj, const char* name, const std::string& v) {
    Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(type.get(), v.empty() ? 1 : v.size());
    H5Tset_strpad(type.get(), H5T_STR_NULLPAD);
    Handle space(H5Screate(H5S_SCALAR), H5Sclose);
    Handle attr(H5Acreate2(obj, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    const std::string data = v.empty() ? std::string(1, '\0') : v;
    if (!attr.ok() || H5Awrite(attr.get(), type.get(), data.data()) < 0) {
        Fail(path, std::string("cannot write attribute ") + name);
    }
}

void WriteDoubleAttr(const std::string& path, hid_t obj, const char* name, double v) {
    Handle space(H5Screate(H5S_SCALAR), H5Sclose);
    Handle attr(H5Acreate2(obj, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                H5Aclose);
    if (!attr.ok() || H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, &v) < 0) {
        Fail(path, std::string("cannot write attribute ") + name);
    }
}

std::string ReadStringAttr(const std::string& where, hid_t obj, const char* name) {
    if (H5Aexists(obj, name) <= 0) Fail(where, std::string("missing attribute '") + name + "'");
    Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
    Handle type(H5Aget_type(attr.get()), H5Tclose);
    if (H5Tget_class(type.get()) != H5T_STRING) Fail(where, std::string(name) + " is not a string");
    if (H5Tis_variable_str(type.get()) > 0) {
        char* s = nullptr;
        Handle mem(H5Tget_native_type(type.get(), H5T_DIR_DEFAULT), H5Tclose);
        if (H5Aread(attr.get(), mem.get(), &s) < 0) Fail(where, std::string("cannot read ") + name);
        std::string out = s ? s : "";
        H5free_memory(s);
        return out;
    }
    const size_t n = H5Tget_size(type.get());
    std::string out(n, '\0');
    if (H5Aread(attr.get(), type.get(), out.data()) < 0) {
        Fail(where, std::string("cannot read ") + name);
    }
    out.resize(out.find('\0') == std::string::npos ? n : out.find('\0'));
    return out;
}

double ReadDoubleAttr(const std::string& where, hid_t obj, const char* name) {
    if (H5Aexists(obj, name) <= 0) Fail(where, std::string("missing attribute '") + name + "'");
    Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
    double v = 0.0;
    if (H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &v) < 0) {
        Fail(where, std::string("cannot read ") + name);
    }
    return v;
}

template <class T>
void WriteDataset(const std::string& path,
                  hid_t group,
                  const char* name,
                  hid_t file_type,
                  hid_t mem_type,
                  const T* data,
                  std::vector<hsize_t> dims) {
    Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
    Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    H5Pset_obj_track_times(dcpl.get(), false);
    Handle ds(H5Dcreate2(group, name, file_type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
              H5Dclose);
    if (!ds.ok() || H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
        Fail(path, std::string("cannot write dataset ") + name);
    }
}

/// Reads a dataset's dims; fails unless its rank is `rank`.
std::vector<hsize_t> DatasetDims(const std::string& where, hid_t ds, int rank, const char* name) {
    Handle space(H5Dget_space(ds), H5Sclose);
    const int r = H5Sget_simple_extent_ndims(space.get());
    if (r != rank) {
        Fail(where, std::string(name) + " has rank " + std::to_string(r) + ", expected " +
                        std::to_string(rank));
    }
    std::vector<hsize_t> dims(static_cast<size_t>(rank));
    H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
    return dims;
}

Handle OpenH5Dataset(const std::string& where, hid_t group, const char* name) {
    if (H5Lexists(group, name, H5P_DEFAULT) <= 0) {
        Fail(where, std::string("missing dataset '") + name + "'");
    }
    Handle ds(H5Dopen2(group, name, H5P_DEFAULT), H5Dclose);
    if (!ds.ok()) Fail(where, std::string("cannot open dataset '") + name + "'");
    return ds;
}

PointCloud ReadCloud(const std::string& where, hid_t group, const char* name) {
    Handle ds = OpenH5Dataset(where, group, name);
    const auto dims = DatasetDims(where, ds.get(), 2, name);
    if (dims[1] != 3) Fail(where, std::string(name) + " must be N x 3");
    PointCloud cloud(static_cast<Eigen::Index>(dims[0]), 3);
    if (H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, cloud.data()) < 0) {
        Fail(where, std::string("cannot read ") + name);
    }
    return cloud;
}

Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> ReadLabels(const std::string& where,
                                                          hid_t group,
                                                          const char* name,
                                                          Eigen::Index expected) {
    Handle ds = OpenH5Dataset(where, group, name);
    const auto dims = DatasetDims(where, ds.get(), 1, name);
    if (static_cast<Eigen::Index>(dims[0]) != expected) {
        Fail(where, std::string(name) + " has " + std::to_string(dims[0]) + " labels for " +
                        std::to_string(expected) + " points");
    }
    Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> labels(expected);
    if (expected > 0 &&
        H5Dread(ds.get(), H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, labels.data()) < 0) {
        Fail(where, std::string("cannot read ") + name);
    }
    return labels;
}

void WritePair(const std::string& path, hid_t file, std::size_t k, const Pair& p) {
    const std::string where = path + ": pair " + std::to_string(k);
    if (p.source_overlap.size() != p.source.rows() || p.target_overlap.size() != p.target.rows()) {
        Fail(where, "overlap labels do not match point counts");
    }
    Handle gcpl = NoTimesGroupPlist();
    Handle g(H5Gcreate2(file, PairGroupName(k).c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT),
             H5Gclose);
    if (!g.ok()) Fail(where, "cannot create group");
    const auto rows = [](const PointCloud& c) { return static_cast<hsize_t>(c.rows()); };
    WriteDataset(path, g.get(), "source", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.source.data(),
                 {rows(p.source), 3});
    WriteDataset(path, g.get(), "target", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.target.data(),
                 {rows(p.target), 3});
    const Eigen::Matrix<double, 4, 4, Eigen::RowMajor> T = p.T_gt;
    WriteDataset(path, g.get(), "T_gt", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, T.data(), {4, 4});
    WriteDataset(path, g.get(), "source_overlap", H5T_STD_U8LE, H5T_NATIVE_UINT8,
                 p.source_overlap.data(), {rows(p.source)});
    WriteDataset(path, g.get(), "target_overlap", H5T_STD_U8LE, H5T_NATIVE_UINT8,
                 p.target_overlap.data(), {rows(p.target)});
    WriteStringAttr(path, g.get(), "shape", p.shape);
    WriteStringAttr(path, g.get(), "category", p.category);
    WriteDoubleAttr(path, g.get(), "source_overlap_ratio", p.source_overlap_ratio);
    WriteDoubleAttr(path, g.get(), "target_overlap_ratio", p.target_overlap_ratio);
    if (!p.meta.empty()) WriteStringAttr(path, g.get(), "meta", p.meta.dump());
}

Pair ReadPair(const std::string& path, hid_t file, std::size_t k) {
    const std::string where = path + ": pair " + std::to_string(k);
    const std::string name = PairGroupName(k);
    if (H5Lexists(file, name.c_str(), H5P_DEFAULT) <= 0) Fail(where, "missing group " + name);
    Handle g(H5Gopen2(file, name.c_str(), H5P_DEFAULT), H5Gclose);
    if (!g.ok()) Fail(where, "cannot open group " + name);
    Pair p;
    p.source = ReadCloud(where, g.get(), "source");
    p.target = ReadCloud(where, g.get(), "target");
    Handle tds = OpenH5Dataset(where, g.get(), "T_gt");
    const auto tdims = DatasetDims(where, tds.get(), 2, "T_gt");
    if (tdims[0] != 4 || tdims[1] != 4) Fail(where, "T_gt must be 4 x 4");
    Eigen::Matrix<double, 4, 4, Eigen::RowMajor> T;
    if (H5Dread(tds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, T.data()) < 0) {
        Fail(where, "cannot read T_gt");
    }
    p.T_gt = T;
    p.source_overlap = ReadLabels(where, g.get(), "source_overlap", p.source.rows());
    p.target_overlap = ReadLabels(where, g.get(), "target_overlap", p.target.rows());
    p.shape = ReadStringAttr(where, g.get(), "shape");
    p.category = ReadStringAttr(where, g.get(), "category");
    p.source_overlap_ratio = ReadDoubleAttr(where, g.get(), "source_overlap_ratio");
    p.target_overlap_ratio = ReadDoubleAttr(where, g.get(), "target_overlap_ratio");
    if (H5Aexists(g.get(), "meta") > 0) {
        try {
            p.meta = nlohmann::json::parse(ReadStringAttr(where, g.get(), "meta"));
        } catch (const nlohmann::json::exception& e) {
            Fail(where, std::string("meta is not valid JSON: ") + e.what());
        }
    }
    return p;
}

/// Opens a pair file read-only and checks its format tag; silences HDF5's own error stack.
Handle OpenForRead(const std::string& path) {
    if (!std::filesystem::exists(path)) Fail(path, "no such file");
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    if (H5Fis_hdf5(path.c_str()) <= 0) {
        Fail(path, "not an HDF5 file (corrupt or truncated?)");
    }
    Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    if (!file.ok()) Fail(path, "cannot open as HDF5 (corrupt or truncated?)");
    if (H5Aexists(file.get(), "format") <= 0 ||
        ReadStringAttr(path, file.get(), "format") != kFormatName) {
        Fail(path, "not a regbench pair file (no format='regbench-pairs' attribute)");
    }
    return file;
}

}  // namespace

void WritePairFile(const std::string& path, const PairSet& set) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    const std::string tmp = path + ".tmp";
    std::filesystem::remove(tmp);
    try {
        Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
        Handle file(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, fcpl.get(), H5P_DEFAULT), H5Fclose);
        if (!file.ok()) Fail(path, "cannot create file");
        WriteStringAttr(path, file.get(), "format", kFormatName);
        WriteDoubleAttr(path, file.get(), "format_version", kFormatVersion);
        WriteDoubleAttr(path, file.get(), "num_pairs", static_cast<double>(set.pairs.size()));
        WriteStringAttr(path, file.get(), "provenance", set.provenance.dump());
        Handle gcpl = NoTimesGroupPlist();
        Handle pairs(H5Gcreate2(file.get(), "/pairs", H5P_DEFAULT, gcpl.get(), H5P_DEFAULT),
                     H5Gclose);
        if (!pairs.ok()) Fail(path, "cannot create /pairs");
        for (std::size_t k = 0; k < set.pairs.size(); ++k)
            WritePair(path, file.get(), k, set.pairs[k]);
    } catch (...) {
        std::filesystem::remove(tmp);
        throw;
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        std::filesystem::remove(tmp);
        Fail(path, "cannot rename temporary file: " + ec.message());
    }
}

std::size_t CountPairs(const std::string& path) {
    Handle file = OpenForRead(path);
    const double n = ReadDoubleAttr(path, file.get(), "num_pairs");
    if (!(n >= 0)) Fail(path, "bad num_pairs");
    return static_cast<std::size_t>(n);
}

PairSet ReadPairFile(const std::string& path) {
    Handle file = OpenForRead(path);
    PairSet set;
    try {
        set.provenance = nlohmann::json::parse(ReadStringAttr(path, file.get(), "provenance"));
    } catch (const nlohmann::json::exception& e) {
        Fail(path, std::string("provenance is not valid JSON: ") + e.what());
    }
    const double n = ReadDoubleAttr(path, file.get(), "num_pairs");
    if (!(n >= 0)) Fail(path, "bad num_pairs");
    set.pairs.reserve(static_cast<std::size_t>(n));
    for (std::size_t k = 0; k < static_cast<std::size_t>(n); ++k) {
        set.pairs.push_back(ReadPair(path, file.get(), k));
    }
    return set;
}

}  // namespace regbench
