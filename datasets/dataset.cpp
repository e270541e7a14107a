// OpenDataset: layout detection, the embedded corpora (cgal, procedural), ModelNet40 OFF trees,
// 7Scenes and generic point-file datasets. HDF5 layouts live in dataset_hdf5.cpp.
#include "datasets/dataset.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <stdexcept>
#include <utility>

#include "core/enum_names.hpp"
#include "core/usage_error.hpp"
#include "datasets/dataset_impl.hpp"
#include "datasets/off_reader.hpp"
#include "datasets/point_file.hpp"
#include "datasets/procedural.hpp"

namespace regbench {
namespace fs = std::filesystem;

namespace {
using detail::DataDir;

using detail::Entry;
using detail::SplitSpec;

int IndexOf(const std::vector<std::string>& names, const std::string& name) {
    return static_cast<int>(std::find(names.begin(), names.end(), name) - names.begin());
}

std::string LowerExtension(const fs::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

detail::EntryLoader MeshLoader(bool normalize) {
    return [normalize](const Entry& e) {
        ShapeRecord r;
        Mesh mesh = ReadOff(e.file);
        if (normalize) {
            try {
                mesh = NormalizeToUnitSphere(mesh);
            } catch (const std::exception& ex) {
                throw std::runtime_error(e.file + ": " + ex.what());
            }
        }
        r.mesh = std::move(mesh);
        return r;
    };
}

detail::EntryLoader PointLoader() {
    return [](const Entry& e) {
        ShapeRecord r;
        r.points = ReadPointFile(e.file, &r.normals);
        return r;
    };
}

/// A split the dataset does not have is a usage error naming the splits it has (`generate
/// --split test` on a folder of point files: exit 2, "... has only split 'all' ...").
void RequireSplit(const SplitSpec& split, const std::string& where, bool has_train_test) {
    const bool ok = split.protocol == "all" ||
                    (has_train_test && split.protocol == "same_category" && split.part != "val");
    if (!ok) {
        throw UsageError(where + ": split '" + split.text + "' not available: " +
                         (has_train_test
                              ? "this dataset has splits 'all', 'train' and 'test'"
                              : "a single file or a folder of point files has only split 'all' "
                                "(every file; pass --split all or leave --split out)"));
    }
}

// ---- cgal: data/corpus.json + data/meshes ----

/// Reads corpus.json, checks every entry names an existing mesh and applies the split. It is
/// one function (a little over 60 lines) because the checks and the split share the parsed
/// entries and each error names the corpus file and the entry.
std::unique_ptr<Dataset> OpenCgal(const SplitSpec& split, const DatasetOptions& options) {
    const fs::path dir = DataDir(options);
    const std::string corpus_path = (dir / "corpus.json").string();
    std::ifstream in(corpus_path);
    if (!in) {
        throw std::runtime_error(corpus_path +
                                 ": cannot open the embedded corpus index (set data_dir or "
                                 "REGBENCH_DATA_DIR to the repository's data/ folder)");
    }
    nlohmann::json corpus;
    try {
        in >> corpus;
    } catch (const std::exception& e) {
        throw std::runtime_error(corpus_path + ": invalid JSON: " + e.what());
    }
    std::vector<std::string> categories;
    std::vector<Entry> all;
    std::map<std::string, std::size_t> by_name;
    try {
        categories = corpus.at("categories").get<std::vector<std::string>>();
        for (const auto& s : corpus.at("shapes")) {
            Entry e;
            e.name = s.at("name").get<std::string>();
            e.category = s.at("category").get<std::string>();
            e.label = IndexOf(categories, e.category);
            if (e.label == static_cast<int>(categories.size())) {
                throw std::runtime_error("shape '" + e.name + "' has unknown category '" +
                                         e.category + "'");
            }
            e.file = (dir / "meshes" / s.at("file").get<std::string>()).string();
            by_name[e.name] = all.size();
            all.push_back(e);
        }
    } catch (const std::exception& e) {
        throw std::runtime_error(corpus_path + ": " + e.what());
    }
    std::vector<Entry> chosen;
    if (split.protocol == "all") {
        chosen = all;
    } else if (split.protocol == "official") {
        throw std::invalid_argument("cgal: split '" + split.text + "' not available");
    } else {
        const nlohmann::json& splits =
            corpus.contains("splits") ? corpus.at("splits") : nlohmann::json();
        if (!splits.is_object() || !splits.contains(split.protocol) ||
            !splits.at(split.protocol).contains(split.part)) {
            throw std::runtime_error(corpus_path + ": no split '" + split.text + "'");
        }
        const nlohmann::json* list = &splits.at(split.protocol).at(split.part);
        for (const auto& name : *list) {
            const auto it = by_name.find(name.get<std::string>());
            if (it == by_name.end()) {
                throw std::runtime_error(corpus_path + ": split '" + split.text +
                                         "' names unknown shape '" + name.get<std::string>() + "'");
            }
            chosen.push_back(all[it->second]);
        }
    }
    for (const Entry& e : chosen) {
        if (!fs::is_regular_file(e.file)) {
            throw std::runtime_error(e.file + ": mesh missing (run scripts/setup_data.sh)");
        }
    }
    return detail::MakeListDataset("cgal", split.text, categories, std::move(chosen),
                                   MeshLoader(options.normalize));
}

// ---- procedural ----

std::unique_ptr<Dataset> OpenProcedural(const SplitSpec& split, const DatasetOptions& options) {
    constexpr int kMinPerCategory = 5;
    if (options.procedural_per_category < kMinPerCategory) {
        throw std::invalid_argument("procedural: procedural_per_category must be >= 5, got " +
                                    std::to_string(options.procedural_per_category));
    }
    if (split.protocol == "official") {
        throw std::invalid_argument("procedural: split '" + split.text + "' not available");
    }
    const std::vector<std::string>& categories = ProceduralCategories();
    const int num = static_cast<int>(categories.size());
    std::vector<Entry> entries;
    for (int label = 0; label < num; ++label) {
        for (int k = 0; k < options.procedural_per_category; ++k) {
            // Same rule as data/corpus.json's splits: val k%5==3, test k%5==4 (same_category);
            // cross_category: first half of the categories is train (+val), second half test.
            const int slot = k % 5;
            const bool first_half = label < num / 2;
            bool keep = split.protocol == "all";
            if (split.protocol == "same_category") {
                keep = split.part == "val"    ? slot == 3
                       : split.part == "test" ? slot == 4
                                              : slot < 3;
            } else if (split.protocol == "cross_category") {
                keep = split.part == "test" ? !first_half
                                            : first_half && ((slot == 3) == (split.part == "val"));
            }
            if (!keep) continue;
            Entry e;
            e.category = categories[static_cast<std::size_t>(label)];
            e.label = label;
            e.index = static_cast<std::size_t>(k);
            char buf[16];
            std::snprintf(buf, sizeof(buf), "_%04d", k);
            e.name = e.category + buf;
            e.file = "procedural:seed=" + std::to_string(options.seed);
            entries.push_back(e);
        }
    }
    const std::uint64_t seed = options.seed;
    const bool normalize = options.normalize;
    return detail::MakeListDataset("procedural", split.text, categories, std::move(entries),
                                   [seed, normalize](const Entry& e) {
                                       ShapeRecord r;
                                       Mesh mesh = MakeProceduralShape(e.label, seed, e.index);
                                       r.mesh = normalize ? NormalizeToUnitSphere(mesh)
                                                          : std::move(mesh);
                                       return r;
                                   });
}

// ---- ModelNet40 OFF tree: <root>/<class>/{train,test}/*.off ----

std::vector<fs::path> SortedFiles(const fs::path& dir, const std::set<std::string>& extensions) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(dir)) {
        const std::string ext = LowerExtension(entry.path());
        if (entry.is_regular_file() && extensions.count(ext) > 0) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    return files;
}

std::vector<std::string> ModelNetOffClasses(const fs::path& root) {
    std::vector<std::string> classes;
    for (const auto& entry : fs::directory_iterator(root)) {
        if (!entry.is_directory()) continue;
        if (fs::is_directory(entry.path() / "train") || fs::is_directory(entry.path() / "test")) {
            classes.push_back(entry.path().filename().string());
        }
    }
    std::sort(classes.begin(), classes.end());
    return classes;
}

std::unique_ptr<Dataset> OpenModelNetOff(const fs::path& root, const SplitSpec& split,
                                         const DatasetOptions& options) {
    const std::vector<std::string> classes = ModelNetOffClasses(root);
    const int num = static_cast<int>(classes.size());
    std::vector<Entry> entries;
    for (int label = 0; label < num; ++label) {
        for (const char* part : {"train", "test"}) {
            const fs::path dir = root / classes[static_cast<std::size_t>(label)] / part;
            if (!fs::is_directory(dir)) continue;
            const bool is_test = std::string(part) == "test";
            std::size_t rank = 0;
            for (const fs::path& file : SortedFiles(dir, {".off"})) {
                if (detail::InOfficialSplit(split, label, num, is_test, rank)) {
                    entries.push_back({file.stem().string(),
                                       classes[static_cast<std::size_t>(label)], label,
                                       file.string(), 0});
                }
                if (!is_test) ++rank;
            }
        }
    }
    if (entries.empty()) {
        throw std::runtime_error(root.string() +
                                 ": ModelNet40 OFF tree has no .off files for split '" +
                                 split.text + "'");
    }
    return detail::MakeListDataset("modelnet40", split.text, classes, std::move(entries),
                                   MeshLoader(options.normalize));
}

// ---- 7Scenes (FMR's package, as OGMM's Scene7 loader reads it) ----

const std::vector<std::string>& SevenScenesTrain() {
    static const std::vector<std::string> s = {"chess",   "fire",       "heads",
                                               "pumpkin", "redkitchen", "stairs"};
    return s;
}

bool HasSevenScenesDirs(const fs::path& dir) {
    for (const auto& entry : fs::directory_iterator(dir)) {
        if (entry.is_directory() && entry.path().filename().string().rfind("7-scenes-", 0) == 0) {
            return true;
        }
    }
    return false;
}

std::unique_ptr<Dataset> OpenSevenScenes(const fs::path& root, const SplitSpec& split) {
    RequireSplit(split, root.string() + " (7Scenes)", true);
    std::vector<std::string> scenes = SevenScenesTrain();
    scenes.push_back("office");
    std::sort(scenes.begin(), scenes.end());  // labels: scene names alphabetically
    std::vector<Entry> entries;
    for (int label = 0; label < static_cast<int>(scenes.size()); ++label) {
        const std::string& scene = scenes[static_cast<std::size_t>(label)];
        const bool is_test = scene == "office";
        if (split.protocol != "all" && is_test != (split.part == "test")) continue;
        const fs::path dir = root / ("7-scenes-" + scene);
        if (!fs::is_directory(dir)) continue;  // partial downloads are allowed
        for (const fs::path& file : SortedFiles(dir, {".ply"})) {
            entries.push_back({scene + "/" + file.stem().string(), scene, label, file.string(), 0});
        }
    }
    if (entries.empty()) {
        throw std::runtime_error(root.string() + ": no 7-scenes-<scene>/*.ply files for split '" +
                                 split.text + "'");
    }
    return detail::MakeListDataset("7scenes", split.text, scenes, std::move(entries),
                                   PointLoader());
}

// ---- generic point files: a file, or a directory tree (category = parent folder) ----

const std::set<std::string>& PointExtensions() {
    static const std::set<std::string> e = {".ply", ".pcd", ".xyz", ".xyzn"};
    return e;
}

std::unique_ptr<Dataset> OpenPointFiles(const fs::path& path, const SplitSpec& split,
                                        const DatasetOptions& options) {
    RequireSplit(split, path.string(), false);
    std::vector<fs::path> files;
    if (fs::is_regular_file(path)) {
        files.push_back(path);
    } else {
        for (const auto& entry : fs::recursive_directory_iterator(path)) {
            const std::string ext = LowerExtension(entry.path());
            if (entry.is_regular_file() && (PointExtensions().count(ext) > 0 || ext == ".off")) {
                files.push_back(entry.path());
            }
        }
        std::sort(files.begin(), files.end());
    }
    if (files.empty()) {
        throw std::runtime_error(path.string() + ": no .ply, .pcd, .xyz, .xyzn or .off files");
    }
    const fs::path base = fs::is_regular_file(path) ? path.parent_path() : path;
    std::set<std::string> category_set;
    std::vector<Entry> entries;
    for (const fs::path& file : files) {
        const fs::path rel_dir = fs::relative(file.parent_path(), base);
        Entry e;
        e.category =
            rel_dir.empty() || rel_dir == "." ? base.filename().string() : rel_dir.string();
        if (e.category.empty()) e.category = "points";
        e.name = (rel_dir.empty() || rel_dir == "." ? fs::path(file.stem()) : rel_dir / file.stem())
                     .string();
        e.file = file.string();
        category_set.insert(e.category);
        entries.push_back(e);
    }
    std::vector<std::string> categories(category_set.begin(), category_set.end());
    for (Entry& e : entries) e.label = IndexOf(categories, e.category);
    const detail::EntryLoader meshes = MeshLoader(options.normalize);
    const detail::EntryLoader points = PointLoader();
    return detail::MakeListDataset(
        "points", split.text, categories, std::move(entries), [meshes, points](const Entry& e) {
            return LowerExtension(e.file) == ".off" ? meshes(e) : points(e);
        });
}

enum class LayoutKind { kModelNetH5, kIclNuim, kSevenScenes, kModelNetOff };

struct Layout {
    LayoutKind kind;
    fs::path dir;
};

constexpr EnumName<LayoutKind> kLayoutNames[] = {
    {LayoutKind::kModelNetH5, "ModelNet40 HDF5"},
    {LayoutKind::kIclNuim, "ICL-NUIM"},
    {LayoutKind::kSevenScenes, "7Scenes"},
    {LayoutKind::kModelNetOff, "ModelNet40 OFF tree"},
};

const char* LayoutName(LayoutKind kind) { return EnumToString(kLayoutNames, kind); }

/// The known layout `dir` itself has, if any. The OFF-tree test (class folders holding train/
/// or test/) is loose, so callers try it last: a data root's `icl_nuim/{train,test}` would pass.
std::optional<LayoutKind> SpecificLayoutOf(const fs::path& dir) {
    if (!fs::is_directory(dir)) return std::nullopt;
    if (detail::LooksLikeModelNetH5Dir(dir.string())) return LayoutKind::kModelNetH5;
    if (detail::LooksLikeIclNuimDir(dir.string())) return LayoutKind::kIclNuim;
    if (HasSevenScenesDirs(dir)) return LayoutKind::kSevenScenes;
    return std::nullopt;
}

std::optional<LayoutKind> LayoutOf(const fs::path& dir) {
    if (const auto kind = SpecificLayoutOf(dir)) return kind;
    if (fs::is_directory(dir) && !ModelNetOffClasses(dir).empty()) return LayoutKind::kModelNetOff;
    return std::nullopt;
}

/// The dataset layout of directory `path`: its own, or that of the one subfolder with a usual
/// name (modelnet40_ply_hdf5_2048, icl_nuim, 7scene, ModelNet40) holding one. A data root
/// holding several datasets (as the authors lay them out) is refused, listing them, so a
/// user never gets one picked silently. nullopt: a plain folder of point files.
std::optional<Layout> DetectLayout(const fs::path& path) {
    if (const auto own = SpecificLayoutOf(path)) return Layout{*own, path};
    std::vector<Layout> found;
    for (const char* sub : {"modelnet40_ply_hdf5_2048", "icl_nuim", "7scene", "ModelNet40"}) {
        if (const auto kind = LayoutOf(path / sub)) found.push_back({*kind, path / sub});
    }
    if (found.size() > 1) {
        std::string list;
        for (const Layout& l : found) {
            list += "\n  " + l.dir.string() + " (" + LayoutName(l.kind) + ")";
        }
        throw std::invalid_argument(
            path.string() + " holds several datasets; pass one of them as --dataset:" + list);
    }
    if (found.size() == 1) return found.front();
    if (fs::is_directory(path) && !ModelNetOffClasses(path).empty()) {
        return Layout{LayoutKind::kModelNetOff, path};
    }
    return std::nullopt;
}

}  // namespace

std::unique_ptr<Dataset> OpenDataset(const std::string& name_or_path, const std::string& split,
                                     const DatasetOptions& options) {
    const SplitSpec spec = detail::ParseSplit(split);
    const fs::path path(name_or_path);
    std::error_code ec;
    const bool exists = fs::exists(path, ec);
    if (!exists && name_or_path == "cgal") return OpenCgal(spec, options);
    if (!exists && name_or_path == "procedural") return OpenProcedural(spec, options);
    if (!exists) {
        throw std::runtime_error(name_or_path +
                                 ": no such dataset file or directory (built-in names: cgal, "
                                 "procedural; indoor-sim with --protocol indoor)");
    }
    if (fs::is_regular_file(path)) {
        const std::string ext = LowerExtension(path);
        if (ext == ".h5" || ext == ".hdf5") return detail::OpenPointsH5(path.string(), spec);
        return OpenPointFiles(path, spec, options);
    }
    if (!fs::is_directory(path)) {
        throw std::runtime_error(name_or_path + ": not a regular file or directory");
    }
    const std::optional<Layout> layout = DetectLayout(path);
    if (layout) {
        switch (layout->kind) {
            case LayoutKind::kModelNetH5:
                return detail::OpenModelNetH5(layout->dir.string(), spec);
            case LayoutKind::kIclNuim:
                return detail::OpenIclNuim(layout->dir.string(), spec);
            case LayoutKind::kSevenScenes:
                return OpenSevenScenes(layout->dir, spec);
            case LayoutKind::kModelNetOff:
                return OpenModelNetOff(layout->dir, spec, options);
        }
    }
    return OpenPointFiles(path, spec, options);
}

}  // namespace regbench

namespace regbench {

void CheckSplitName(const std::string& split) { (void)detail::ParseSplit(split); }

std::string DefaultSplit(const std::string& name_or_path) {
    const fs::path path(name_or_path);
    std::error_code ec;
    if (!fs::exists(path, ec)) return "test";  // named datasets (cgal, procedural, indoor-sim)
    // A single file (a ModelNet40 .h5, a DeepGMR test file, a point file) has only "all".
    if (fs::is_regular_file(path)) return "all";
    return DetectLayout(path) ? "test" : "all";  // a folder of point files has no splits
}

}  // namespace regbench
