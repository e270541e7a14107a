#include "protocols/pair_file.hpp"

#include <fcntl.h>
#include <hdf5.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/LU>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define REGBENCH_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(REGBENCH_ASAN)
#include <sanitizer/common_interface_defs.h>
#define REGBENCH_ASAN_DEATH_CALLBACK 1
#endif

#include "core/atomic_file.hpp"
#include "core/coordinate_limit.hpp"
#include "core/json_limits.hpp"
#include "protocols/hdf5_handle.hpp"

namespace regbench {
namespace {

constexpr const char* kFormatName = "regbench-pairs";
constexpr int kFormatVersion = 1;
/// Tolerance on |R^T R - I| and on T_gt's last row (f64 round-off of a stored rotation).
constexpr double kRigidTolerance = 1e-6;

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

std::string ReadStringAttrBytes(const std::string& where, hid_t obj, const char* name);

/// The provenance keys readers use with a fixed type: a mistyped one (a number for `dataset`)
/// made a bare type_error.302 later, in whichever command read it.
void CheckProvenanceTypes(const std::string& path, const nlohmann::json& p) {
    if (!p.is_object()) Fail(path, "provenance is not a JSON object");
    for (const char* key : {"dataset", "protocol", "pairing", "content_hash", "format"}) {
        if (p.contains(key) && !p.at(key).is_string()) {
            Fail(path,
                 std::string("provenance key '") + key + "' must be a string, got " +
                     p.at(key).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
        }
    }
    if (p.contains("params") && !p.at("params").is_object()) {
        Fail(path, "provenance key 'params' must be an object");
    }
}

/// A string attribute, refused naming the file/group and the key unless it is UTF-8 (every
/// one ends up in JSON rows and reports, where other bytes made a bare type_error.316).
std::string ReadStringAttr(const std::string& where, hid_t obj, const char* name) {
    std::string s = ReadStringAttrBytes(where, obj, name);
    if (!IsValidUtf8(s)) Fail(where, std::string("attribute '") + name + "' is not valid UTF-8");
    return s;
}

std::string ReadStringAttrBytes(const std::string& where, hid_t obj, const char* name) {
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
    // Attributes live in the object header (64 KiB) or dense storage; anything bigger is a lie.
    if (n == 0 || n > (std::size_t{1} << 28)) {
        Fail(where, std::string(name) + " declares an implausible size " + std::to_string(n));
    }
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
void WriteDataset(const std::string& path, hid_t group, const char* name, hid_t file_type,
                  hid_t mem_type, const T* data, std::vector<hsize_t> dims) {
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

/// Pair files hold hard links only: an external link names another file (a FIFO there hung
/// `run` and `inspect` for ever, a device or any local file was read as coordinates) and a soft
/// link another object; neither is ever written by regbench. Checked without traversing it.
void RequireHardLink(const std::string& where, hid_t loc, const std::string& name) {
    H5L_info_t info{};
    if (H5Lget_info(loc, name.c_str(), &info, H5P_DEFAULT) < 0) {
        Fail(where, "cannot read the link '" + name + "'");
    }
    if (info.type != H5L_TYPE_HARD) {
        Fail(where, "'" + name + "' is " +
                        (info.type == H5L_TYPE_EXTERNAL ? "an external link (to another file)"
                                                        : std::string("a soft or user link")) +
                        "; pair files may hold no links to other objects or files");
    }
}

/// A dataset's bytes must live in the pair file: external storage (raw data in other files,
/// H5Pset_external) or a virtual dataset (mapped from other files) is refused by name.
void RequireStoredInFile(const std::string& where, hid_t ds, const char* name) {
    Handle dcpl(H5Dget_create_plist(ds), H5Pclose);
    if (!dcpl.ok()) Fail(where, std::string("cannot read the storage of '") + name + "'");
    if (H5Pget_external_count(dcpl.get()) != 0) {
        Fail(where, std::string("dataset '") + name +
                        "' uses external storage (its data in other files); pair files must "
                        "hold their data");
    }
    if (H5Pget_layout(dcpl.get()) == H5D_VIRTUAL) {
        Fail(where, std::string("dataset '") + name +
                        "' is a virtual dataset (mapped from other files); pair files must hold "
                        "their data");
    }
}

Handle OpenH5Dataset(const std::string& where, hid_t group, const char* name) {
    if (H5Lexists(group, name, H5P_DEFAULT) <= 0) {
        Fail(where, std::string("missing dataset '") + name + "'");
    }
    RequireHardLink(where, group, name);
    Handle ds(H5Dopen2(group, name, H5P_DEFAULT), H5Dclose);
    if (!ds.ok()) Fail(where, std::string("cannot open dataset '") + name + "'");
    RequireStoredInFile(where, ds.get(), name);
    return ds;
}

/// How far a dataset's decoded size may exceed the bytes it occupies on disk (compression).
/// regbench writes uncompressed f64 (ratio 1); float32 storage doubles it; gzip'd real clouds
/// stay far below this. A header declaring 1e8 points in a 790 KB file does not.
constexpr double kMaxExpansion = 64.0;

/// Refuses a dataset whose declared size cannot be backed by the file, before allocating.
void CheckBacked(const std::string& where, const char* name, hid_t ds, double decoded_bytes,
                 std::uintmax_t file_size) {
    const double stored = static_cast<double>(H5Dget_storage_size(ds));
    if (decoded_bytes > 0 && (stored > static_cast<double>(file_size) ||
                              decoded_bytes > std::max(stored, 1.0) * kMaxExpansion)) {
        Fail(where, std::string(name) + " declares " + std::to_string(decoded_bytes / 1e6) +
                        " MB of data but only " + std::to_string(stored / 1e6) +
                        " MB are stored in the file (corrupt or hostile header)");
    }
}

/// Every coordinate must be finite and fit in a float: PCL's methods convert to float and
/// abort on overflow, and no real cloud comes near 3.4e38.
void CheckValues(const std::string& where, const char* name, const double* v, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(v[i])) {
            Fail(where,
                 std::string(name) + " has a non-finite value (row " + std::to_string(i / 3) + ")");
        }
        if (std::abs(v[i]) > kMaxCoordinate) {
            Fail(where, std::string(name) + " row " + std::to_string(i / 3) + ": magnitude " +
                            std::to_string(v[i]) +
                            " is beyond the coordinate limit |x| <= 1e15 (does not fit in a "
                            "float or in the methods' float arithmetic)");
        }
    }
}

PointCloud ReadCloud(const std::string& where, hid_t group, const char* name,
                     std::uintmax_t file_size) {
    Handle ds = OpenH5Dataset(where, group, name);
    const auto dims = DatasetDims(where, ds.get(), 2, name);
    if (dims[1] != 3) Fail(where, std::string(name) + " must be N x 3");
    if (dims[0] == 0) Fail(where, std::string(name) + " cloud is empty");
    CheckBacked(where, name, ds.get(), static_cast<double>(dims[0]) * 3.0 * sizeof(double),
                file_size);
    PointCloud cloud(static_cast<Eigen::Index>(dims[0]), 3);
    if (H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, cloud.data()) < 0) {
        Fail(where, std::string("cannot read ") + name);
    }
    CheckValues(where, name, cloud.data(), static_cast<std::size_t>(cloud.size()));
    return cloud;
}

Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> ReadLabels(const std::string& where, hid_t group,
                                                          const char* name, Eigen::Index expected) {
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

/// T_gt must be a rigid motion: finite, last row 0 0 0 1, R orthonormal with det +1 (a scaled,
/// reflected or all-zero "ground truth" would be scored as if it were one).
void CheckRigid(const std::string& where, const Eigen::Matrix4d& T) {
    if (!T.allFinite()) Fail(where, "T_gt has a non-finite entry");
    if ((T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > kRigidTolerance) {
        Fail(where, "T_gt's last row is not 0 0 0 1");
    }
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    const double orth = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (orth > kRigidTolerance) {
        Fail(where,
             "T_gt's rotation is not orthonormal (max |R^T R - I| = " + std::to_string(orth) + ")");
    }
    if (R.determinant() < 0) Fail(where, "T_gt is a reflection (det R = -1)");
    if (T.topRightCorner<3, 1>().cwiseAbs().maxCoeff() > kMaxCoordinate) {
        Fail(where, "T_gt's translation is beyond the coordinate limit |x| <= 1e15");
    }
}

Pair ReadPair(const std::string& path, hid_t file, std::size_t k, std::uintmax_t file_size) {
    const std::string where = path + ": pair " + std::to_string(k);
    const std::string name = PairGroupName(k);
    if (H5Lexists(file, name.c_str(), H5P_DEFAULT) <= 0) Fail(where, "missing group " + name);
    RequireHardLink(where, file, name);
    Handle g(H5Gopen2(file, name.c_str(), H5P_DEFAULT), H5Gclose);
    if (!g.ok()) Fail(where, "cannot open group " + name);
    Pair p;
    p.source = ReadCloud(where, g.get(), "source", file_size);
    p.target = ReadCloud(where, g.get(), "target", file_size);
    Handle tds = OpenH5Dataset(where, g.get(), "T_gt");
    const auto tdims = DatasetDims(where, tds.get(), 2, "T_gt");
    if (tdims[0] != 4 || tdims[1] != 4) Fail(where, "T_gt must be 4 x 4");
    Eigen::Matrix<double, 4, 4, Eigen::RowMajor> T;
    if (H5Dread(tds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, T.data()) < 0) {
        Fail(where, "cannot read T_gt");
    }
    p.T_gt = T;
    CheckRigid(where, p.T_gt);
    p.source_overlap = ReadLabels(where, g.get(), "source_overlap", p.source.rows());
    p.target_overlap = ReadLabels(where, g.get(), "target_overlap", p.target.rows());
    p.shape = ReadStringAttr(where, g.get(), "shape");
    p.category = ReadStringAttr(where, g.get(), "category");
    p.source_overlap_ratio = ReadDoubleAttr(where, g.get(), "source_overlap_ratio");
    p.target_overlap_ratio = ReadDoubleAttr(where, g.get(), "target_overlap_ratio");
    for (const double r : {p.source_overlap_ratio, p.target_overlap_ratio}) {
        if (!(r >= 0.0 && r <= 1.0)) Fail(where, "overlap ratio outside [0, 1]");
    }
    if (H5Aexists(g.get(), "meta") > 0) {
        try {
            p.meta = ParseJsonBounded(ReadStringAttr(where, g.get(), "meta"), where + " meta");
        } catch (const nlohmann::json::exception& e) {
            Fail(where, std::string("meta is not valid JSON: ") + e.what());
        }
    }
    return p;
}

/// Opens a pair file read-only and checks its format tag; silences HDF5's own error stack.
Handle OpenForRead(const std::string& path) {
    if (!std::filesystem::exists(path)) Fail(path, "no such file");
    if (!std::filesystem::is_regular_file(path)) Fail(path, "not a regular file");
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
    const double version = ReadDoubleAttr(path, file.get(), "format_version");
    if (version != kFormatVersion) {
        Fail(path, "format_version " + std::to_string(version) +
                       " is not supported (this regbench "
                       "reads version " +
                       std::to_string(kFormatVersion) + ")");
    }
    return file;
}

/// num_pairs must be a whole number equal to the groups present under /pairs, so neither a
/// header saying 1e30 nor 2.5 nor a file missing groups reads as something else.
std::size_t CheckedPairCount(const std::string& path, hid_t file) {
    const double n = ReadDoubleAttr(path, file, "num_pairs");
    if (!std::isfinite(n) || n < 0 || n != std::floor(n)) {
        Fail(path, "num_pairs = " + std::to_string(n) + " is not a whole number >= 0");
    }
    if (H5Lexists(file, "pairs", H5P_DEFAULT) <= 0) Fail(path, "missing group /pairs");
    RequireHardLink(path, file, "pairs");
    Handle pairs(H5Gopen2(file, "pairs", H5P_DEFAULT), H5Gclose);
    H5G_info_t info{};
    if (!pairs.ok() || H5Gget_info(pairs.get(), &info) < 0) Fail(path, "cannot open /pairs");
    if (static_cast<double>(info.nlinks) != n) {
        Fail(path, "num_pairs says " +
                       std::to_string(static_cast<unsigned long long>(std::min(n, 1e19))) +
                       " but /pairs holds " + std::to_string(info.nlinks) + " groups");
    }
    return static_cast<std::size_t>(info.nlinks);
}

std::uintmax_t FileSize(const std::string& path) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) Fail(path, "cannot stat: " + ec.message());
    return size;
}

/// Runs `read` (a complete read of `path`) in a forked child first. libhdf5 1.10 is not safe on
/// corrupt files: fuzz_pair_file found a heap-use-after-free inside it (H5O__msg_iterate_real)
/// on a damaged object header, which regbench's own checks cannot see before HDF5 parses the
/// header. A child that dies (signal, sanitizer report) turns into an error naming the file; a
/// child that read the file, or that threw (the parent repeats the read and throws the same,
/// deterministic error with its message), lets the parent read it in-process. Costs one fork
/// and a second read of the file.
template <class Read>
void ReadInChildFirst(const std::string& path, const Read& read) {
    std::fflush(nullptr);
    const pid_t pid = fork();
    if (pid < 0) return;  // cannot fork (process limit): read in-process as before
    if (pid == 0) {
#ifdef REGBENCH_ASAN_DEATH_CALLBACK
        __sanitizer_set_death_callback(nullptr);  // a fuzzer's crash hook must not fire here
#endif
        for (int sig : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) std::signal(sig, SIG_DFL);
        const int null_fd = open("/dev/null", O_WRONLY);
        if (null_fd >= 0) dup2(null_fd, STDERR_FILENO);  // the library's own noise
        int code = 0;
        try {
            read();
        } catch (...) {
            code = 3;
        }
        _exit(code);
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR) return;
    }
    if (WIFEXITED(status) && (WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 3)) return;
    Fail(path, "the HDF5 library failed reading it (" +
                   (WIFSIGNALED(status) ? "signal " + std::to_string(WTERMSIG(status))
                                        : "exit status " + std::to_string(WEXITSTATUS(status))) +
                   "): corrupt or not a regbench pair file");
}

std::size_t CountPairsInProcess(const std::string& path) {
    Handle file = OpenForRead(path);
    return CheckedPairCount(path, file.get());
}

PairSet ReadPairFileInProcess(const std::string& path) {
    Handle file = OpenForRead(path);
    const std::uintmax_t file_size = FileSize(path);
    PairSet set;
    try {
        set.provenance =
            ParseJsonBounded(ReadStringAttr(path, file.get(), "provenance"), path + " provenance");
        CheckProvenanceTypes(path, set.provenance);
    } catch (const nlohmann::json::exception& e) {
        Fail(path, std::string("provenance is not valid JSON: ") + e.what());
    }
    const std::size_t n = CheckedPairCount(path, file.get());
    for (std::size_t k = 0; k < n; ++k) {
        set.pairs.push_back(ReadPair(path, file.get(), k, file_size));
    }
    return set;
}

}  // namespace

void WritePairFile(const std::string& path, const PairSet& set) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    AtomicFile out(path);  // refuses directories and special files; removes the temp on failure
    // HDF5 builds the file in memory (core driver, no backing store) and AtomicFile writes the
    // image with checked writes. HDF5 never meets a full disk itself: when its own write or
    // flush fails it cannot close the file, and its exit handler then crashes the process
    // (SIGSEGV after "wrote"), which is what happened on a full disk before.
    std::vector<char> image;
    {
        Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
        H5Pset_fapl_core(fapl.get(), std::size_t{1} << 20, /*backing_store=*/0);
        // Strong close: H5Fclose closes everything, or reports why it could not.
        H5Pset_fclose_degree(fapl.get(), H5F_CLOSE_STRONG);
        Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
        Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get()), H5Fclose);
        if (!file.ok()) Fail(path, "cannot create file");
        WriteStringAttr(path, file.get(), "format", kFormatName);
        WriteDoubleAttr(path, file.get(), "format_version", kFormatVersion);
        WriteDoubleAttr(path, file.get(), "num_pairs", static_cast<double>(set.pairs.size()));
        WriteStringAttr(path, file.get(), "provenance", set.provenance.dump());
        {
            Handle gcpl = NoTimesGroupPlist();
            Handle pairs(H5Gcreate2(file.get(), "/pairs", H5P_DEFAULT, gcpl.get(), H5P_DEFAULT),
                         H5Gclose);
            if (!pairs.ok()) Fail(path, "cannot create /pairs");
        }
        for (std::size_t k = 0; k < set.pairs.size(); ++k)
            WritePair(path, file.get(), k, set.pairs[k]);
        if (H5Fflush(file.get(), H5F_SCOPE_GLOBAL) < 0) Fail(path, "cannot flush");
        const ssize_t size = H5Fget_file_image(file.get(), nullptr, 0);
        if (size <= 0) Fail(path, "cannot get the file image");
        image.resize(static_cast<std::size_t>(size));
        if (H5Fget_file_image(file.get(), image.data(), image.size()) != size) {
            Fail(path, "cannot get the file image");
        }
    }
    out.Write(std::string_view(image.data(), image.size()));  // checked: ENOSPC, EFBIG, EIO
    out.Commit();
}

std::size_t CountPairs(const std::string& path) {
    ReadInChildFirst(path, [&] { CountPairsInProcess(path); });
    return CountPairsInProcess(path);
}

PairSet ReadPairFile(const std::string& path) {
    ReadInChildFirst(path, [&] { ReadPairFileInProcess(path); });
    return ReadPairFileInProcess(path);
}

}  // namespace regbench
