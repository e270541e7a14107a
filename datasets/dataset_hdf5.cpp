// HDF5 datasets: the ModelNet40 release (modelnet40_ply_hdf5_2048), DeepGMR-style files
// (`points`, or `source`/`target`/`transform`) and ICL-NUIM as OGMM/DeepGMR store it.
#include <hdf5.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "datasets/dataset_impl.hpp"
#include "protocols/hdf5_handle.hpp"

namespace regbench::detail {
namespace fs = std::filesystem;

namespace {

using H5Id = H5Handle;

/// A whole numeric dataset, converted by HDF5 to T.
template <typename T>
struct Array {
    std::vector<hsize_t> dims;
    std::vector<T> values;
};

template <typename T>
hid_t NativeType();
template <>
hid_t NativeType<float>() {
    return H5T_NATIVE_FLOAT;
}
template <>
hid_t NativeType<double>() {
    return H5T_NATIVE_DOUBLE;
}
template <>
hid_t NativeType<int>() {
    return H5T_NATIVE_INT;
}

std::string ShapeString(const std::vector<hsize_t>& dims) {
    std::string s = "[";
    for (std::size_t i = 0; i < dims.size(); ++i) s += (i ? ", " : "") + std::to_string(dims[i]);
    return s + "]";
}

/// Largest dataset a file may declare: 4 GiB, 80x the largest file of the ModelNet40 release.
constexpr hsize_t kMaxDatasetBytes = hsize_t{4} << 30;

class H5File {
public:
    explicit H5File(const std::string& path)
        : path_(path),
          file_((H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr),
                 H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT)),
                H5Fclose) {
        if (!fs::is_regular_file(path)) throw std::runtime_error(path + ": no such HDF5 file");
        if (!file_.ok()) throw std::runtime_error(path + ": not a readable HDF5 file");
    }
    bool Has(const std::string& name) const {
        return H5Lexists(file_.get(), name.c_str(), H5P_DEFAULT) > 0;
    }
    template <typename T>
    Array<T> Read(const std::string& name) const {
        const std::string where = path_ + ": dataset '" + name + "'";
        if (!Has(name)) throw std::runtime_error(where + " is missing");
        H5Id ds(H5Dopen2(file_.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
        if (!ds.ok()) throw std::runtime_error(where + " cannot be opened");
        H5Id space(H5Dget_space(ds.get()), H5Sclose);
        const int rank = H5Sget_simple_extent_ndims(space.get());
        if (rank < 1) throw std::runtime_error(where + " has no shape");
        Array<T> a;
        a.dims.resize(static_cast<std::size_t>(rank));
        H5Sget_simple_extent_dims(space.get(), a.dims.data(), nullptr);
        // A tiny file can declare any shape (its storage allocated late or compressed): the
        // declared size is checked before anything is allocated for it.
        hsize_t count = 1;
        bool too_large = false;
        for (hsize_t d : a.dims) {
            too_large = too_large || (d != 0 && count > kMaxDatasetBytes / sizeof(T) / d);
            count *= d;
        }
        if (too_large || count > kMaxDatasetBytes / sizeof(T)) {
            throw std::runtime_error(where + " declares shape " + ShapeString(a.dims) +
                                     ", more than the " + std::to_string(kMaxDatasetBytes >> 30) +
                                     " GiB a dataset may hold (a ModelNet40 file holds 50 MB)");
        }
        try {
            a.values.resize(count);
        } catch (const std::bad_alloc&) {
            throw std::runtime_error(where + " declares shape " + ShapeString(a.dims) +
                                     ", which does not fit in memory");
        }
        if (count > 0 && H5Dread(ds.get(), NativeType<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT,
                                 a.values.data()) < 0) {
            throw std::runtime_error(where + " cannot be read (corrupt or truncated file?)");
        }
        return a;
    }
    const std::string& path() const { return path_; }

private:
    std::string path_;
    H5Id file_;
};

/// Checks a cloud array is [S, P, 3] (P >= 1) and returns S.
std::size_t RequireClouds(const Array<float>& a, const std::string& path, const std::string& name) {
    if (a.dims.size() != 3 || a.dims[2] != 3 || a.dims[1] == 0) {
        throw std::runtime_error(path + ": dataset '" + name + "' has shape " +
                                 ShapeString(a.dims) + ", expected [S, P, 3]");
    }
    return static_cast<std::size_t>(a.dims[0]);
}

PointCloud CloudAt(const Array<float>& a, std::size_t i) {
    const auto p = static_cast<Eigen::Index>(a.dims[1]);
    PointCloud cloud(p, 3);
    const float* src = a.values.data() + i * static_cast<std::size_t>(p) * 3;
    for (Eigen::Index k = 0; k < p * 3; ++k) cloud.data()[k] = static_cast<double>(src[k]);
    return cloud;
}

/// Class labels [S] or [S, 1]; each must index `num_categories`.
std::vector<int> ReadLabels(const H5File& f, std::size_t count, int num_categories) {
    const Array<int> labels = f.Read<int>("label");
    if (labels.values.size() != count || (labels.dims.size() == 2 && labels.dims[1] != 1) ||
        labels.dims.size() > 2) {
        throw std::runtime_error(f.path() + ": dataset 'label' has shape " +
                                 ShapeString(labels.dims) + ", expected [" + std::to_string(count) +
                                 ", 1]");
    }
    for (int v : labels.values) {
        if (v < 0 || v >= num_categories) {
            throw std::runtime_error(f.path() + ": label " + std::to_string(v) + " outside [0, " +
                                     std::to_string(num_categories) + ")");
        }
    }
    return labels.values;
}

/// shape_names.txt beside the files (one name per line), else class_00 ... class_39.
std::vector<std::string> CategoryNames(const fs::path& dir) {
    constexpr int kModelNetClasses = 40;
    std::vector<std::string> names;
    std::ifstream in(dir / "shape_names.txt");
    for (std::string line; std::getline(in, line);) {
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
        if (!line.empty()) names.push_back(line);
    }
    if (names.empty()) {
        for (int k = 0; k < kModelNetClasses; ++k) {
            names.push_back((k < 10 ? "class_0" : "class_") + std::to_string(k));
        }
    }
    return names;
}

/// Clouds (and optional normals / partner clouds) of one file, shared by the loader.
struct Block {
    Array<float> points;
    Array<float> normals;  ///< empty when absent
    Array<float> target;   ///< pair files only
    Array<double> transforms;
};

std::vector<fs::path> ModelNetFiles(const fs::path& dir, const std::string& part) {
    std::vector<fs::path> files;
    const fs::path list = dir / (part + "_files.txt");
    if (fs::is_regular_file(list)) {
        // The release lists "data/modelnet40_ply_hdf5_2048/ply_data_train0.h5": keep the name.
        std::ifstream in(list);
        for (std::string line; std::getline(in, line);) {
            while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
            if (line.empty()) continue;
            const fs::path file = dir / fs::path(line).filename();
            if (!fs::is_regular_file(file)) {
                throw std::runtime_error(list.string() + ": listed file " + file.string() +
                                         " is missing");
            }
            files.push_back(file);
        }
        return files;
    }
    const std::string prefix = "ply_data_" + part;
    for (const auto& entry : fs::directory_iterator(dir)) {
        const std::string name = entry.path().filename().string();
        if (entry.is_regular_file() && name.rfind(prefix, 0) == 0 &&
            entry.path().extension() == ".h5") {
            files.push_back(entry.path());
        }
    }
    std::sort(files.begin(), files.end());  // the authors' glob is unsorted; regbench sorts
    return files;
}

using BlockMap = std::map<std::string, std::shared_ptr<const Block>>;

EntryLoader BlockLoader(std::shared_ptr<const BlockMap> blocks) {
    return [blocks](const Entry& e) {
        const Block& b = *blocks->at(e.file);
        ShapeRecord r;
        r.points = CloudAt(b.points, e.index);
        if (!b.normals.values.empty()) r.normals = CloudAt(b.normals, e.index);
        if (!b.target.values.empty()) {
            r.target = CloudAt(b.target, e.index);
            Transform T;
            const double* src = b.transforms.values.data() + e.index * 16;
            for (int i = 0; i < 4; ++i) {
                for (int j = 0; j < 4; ++j) T(i, j) = src[i * 4 + j];
            }
            r.T_target_points = T;
        }
        return r;
    };
}

std::string RowName(const fs::path& file, std::size_t row) {
    char buf[24];
    std::snprintf(buf, sizeof(buf), "/%05zu", row);
    return file.stem().string() + buf;
}

/// Reads a DeepGMR-style file: `points`, or `source` + `target` + `transform`.
std::shared_ptr<Block> ReadCloudFile(const H5File& f) {
    auto block = std::make_shared<Block>();
    if (f.Has("points")) {
        block->points = f.Read<float>("points");
        RequireClouds(block->points, f.path(), "points");
        return block;
    }
    if (f.Has("source") && f.Has("target") && f.Has("transform")) {
        block->points = f.Read<float>("source");
        block->target = f.Read<float>("target");
        block->transforms = f.Read<double>("transform");
        const std::size_t s = RequireClouds(block->points, f.path(), "source");
        if (RequireClouds(block->target, f.path(), "target") != s) {
            throw std::runtime_error(f.path() + ": 'source' and 'target' differ in count");
        }
        const auto& td = block->transforms.dims;
        if (td.size() != 3 || td[0] != s || td[1] != 4 || td[2] != 4) {
            throw std::runtime_error(f.path() + ": dataset 'transform' has shape " +
                                     ShapeString(td) + ", expected [" + std::to_string(s) +
                                     ", 4, 4]");
        }
        return block;
    }
    throw std::runtime_error(f.path() +
                             ": expected datasets 'data' (+ 'label'), 'points', or "
                             "'source' + 'target' + 'transform'");
}

}  // namespace

bool LooksLikeModelNetH5Dir(const std::string& dir) {
    const fs::path d(dir);
    if (fs::is_regular_file(d / "train_files.txt") || fs::is_regular_file(d / "test_files.txt")) {
        return true;
    }
    return !ModelNetFiles(d, "train").empty() || !ModelNetFiles(d, "test").empty();
}

std::unique_ptr<Dataset> OpenModelNetH5(const std::string& dir, const SplitSpec& split) {
    const std::vector<std::string> categories = CategoryNames(dir);
    const int num = static_cast<int>(categories.size());
    auto blocks = std::make_shared<BlockMap>();
    std::vector<Entry> entries;
    std::vector<std::size_t> train_rank(categories.size(), 0);
    for (const std::string part : {"train", "test"}) {
        const bool is_test = part == "test";
        // Only the files the split can use are read (train/val never need the test files).
        const bool needed = split.protocol == "all" || (split.part == "test") == is_test;
        if (!needed) continue;
        const std::vector<fs::path> files = ModelNetFiles(dir, part);
        if (files.empty()) {
            throw std::runtime_error(dir + ": no ModelNet40 " + part + " files (ply_data_" + part +
                                     "*.h5 or " + part + "_files.txt)");
        }
        for (const fs::path& file : files) {
            const H5File f(file.string());
            auto block = std::make_shared<Block>();
            block->points = f.Read<float>("data");
            const std::size_t count = RequireClouds(block->points, f.path(), "data");
            if (f.Has("normal")) {
                block->normals = f.Read<float>("normal");
                if (block->normals.dims != block->points.dims) {
                    throw std::runtime_error(f.path() + ": 'normal' shape " +
                                             ShapeString(block->normals.dims) +
                                             " differs from 'data'");
                }
            }
            const std::vector<int> labels = ReadLabels(f, count, num);
            (*blocks)[f.path()] = block;
            for (std::size_t i = 0; i < count; ++i) {
                const int label = labels[i];
                const std::size_t rank =
                    is_test ? 0 : train_rank[static_cast<std::size_t>(label)]++;
                if (InOfficialSplit(split, label, num, is_test, rank)) {
                    entries.push_back({RowName(file, i),
                                       categories[static_cast<std::size_t>(label)], label, f.path(),
                                       i});
                }
            }
        }
    }
    return MakeListDataset("modelnet40_h5", split.text, categories, std::move(entries),
                           BlockLoader(blocks));
}

bool LooksLikeIclNuimDir(const std::string& dir) {
    const fs::path d(dir);
    return fs::is_regular_file(d / "train" / "icl_nuim.h5") ||
           fs::is_regular_file(d / "test" / "icl_nuim.h5");
}

std::unique_ptr<Dataset> OpenIclNuim(const std::string& dir, const SplitSpec& split) {
    const bool ok =
        split.protocol == "all" || (split.protocol == "same_category" && split.part != "val");
    if (!ok) {
        throw std::invalid_argument(dir + " (ICL-NUIM): split '" + split.text +
                                    "' not available (use all, train or test)");
    }
    auto blocks = std::make_shared<BlockMap>();
    std::vector<Entry> entries;
    for (const std::string part : {"train", "test"}) {
        if (split.protocol != "all" && split.part != part) continue;
        const fs::path file = fs::path(dir) / part / "icl_nuim.h5";
        const H5File f(file.string());  // throws naming the file when it is missing
        auto block = ReadCloudFile(f);
        const std::size_t count = static_cast<std::size_t>(block->points.dims[0]);
        (*blocks)[f.path()] = block;
        for (std::size_t i = 0; i < count; ++i) {
            entries.push_back({part + RowName("", i), "icl_nuim", 0, f.path(), i});
        }
    }
    return MakeListDataset("icl_nuim", split.text, {"icl_nuim"}, std::move(entries),
                           BlockLoader(blocks));
}

std::unique_ptr<Dataset> OpenPointsH5(const std::string& path, const SplitSpec& split) {
    if (split.protocol != "all") {
        throw std::invalid_argument(path + ": a single HDF5 file only has split 'all'");
    }
    const H5File f(path);
    std::shared_ptr<Block> block;
    std::vector<std::string> categories;
    std::vector<int> labels;
    std::string kind = "points_h5";
    if (f.Has("data")) {  // one file of the ModelNet40 release
        block = std::make_shared<Block>();
        block->points = f.Read<float>("data");
        RequireClouds(block->points, path, "data");
        if (f.Has("normal")) block->normals = f.Read<float>("normal");
        if (block->normals.dims != block->points.dims) block->normals = {};
        kind = "modelnet40_h5";
    } else {
        block = ReadCloudFile(f);
    }
    const std::size_t count = static_cast<std::size_t>(block->points.dims[0]);
    if (f.Has("label")) {
        categories = CategoryNames(fs::path(path).parent_path());
        labels = ReadLabels(f, count, static_cast<int>(categories.size()));
    } else {
        categories = {fs::path(path).stem().string()};
        labels.assign(count, 0);
    }
    auto blocks = std::make_shared<BlockMap>();
    (*blocks)[path] = block;
    std::vector<Entry> entries;
    for (std::size_t i = 0; i < count; ++i) {
        entries.push_back({RowName(path, i), categories[static_cast<std::size_t>(labels[i])],
                           labels[i], path, i});
    }
    return MakeListDataset(kind, split.text, categories, std::move(entries), BlockLoader(blocks));
}

}  // namespace regbench::detail
