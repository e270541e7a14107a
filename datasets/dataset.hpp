#pragma once
// Datasets of shapes and scans behind one small interface (layouts: docs/datasets.md).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "protocols/mesh.hpp"

namespace regbench {

/// One item of a dataset: a mesh (mesh datasets) or a point cloud (point datasets).
struct ShapeRecord {
    std::string name;          ///< unique within the dataset, e.g. "bunny", "airplane_0627"
    std::string category;      ///< class / scene name
    int label = -1;            ///< index of `category` in Dataset::Categories()
    std::optional<Mesh> mesh;  ///< mesh datasets: the mesh (in the unit sphere if normalised)
    PointCloud points;         ///< point datasets: the cloud; empty for mesh datasets
    Normals normals;           ///< per-point normals when the file has them, else empty
    /// Files that store fixed pairs (DeepGMR-style test .h5: source/target/transform) give the
    /// partner cloud and the transform mapping `points` onto it; both unset otherwise.
    std::optional<PointCloud> target;
    std::optional<Transform> T_target_points;
    std::string file;  ///< file the record came from (provenance, error messages)
};

struct DatasetOptions {
    /// Directory holding corpus.json and meshes/ for "cgal". Empty: regbench::DataDir()
    /// ($REGBENCH_DATA_DIR, else the source tree's data/; core/data_dir.hpp).
    std::string data_dir;
    bool normalize = true;             ///< mesh datasets: centre and scale into the unit sphere
    std::uint64_t seed = 0;            ///< "procedural": generator seed
    int procedural_per_category = 20;  ///< "procedural": shapes per category, >= 5
};

/// A finite, indexable dataset. Get() reads lazily and is safe to call from several threads.
class Dataset {
public:
    virtual ~Dataset() = default;
    /// Dataset kind: "cgal", "procedural", "modelnet40", "modelnet40_h5", "7scenes", "icl_nuim",
    /// "points_h5", "points".
    virtual std::string Kind() const = 0;
    /// Split this object was opened with.
    virtual std::string Split() const = 0;
    /// All category names of the dataset, in label order (not only this split's).
    virtual const std::vector<std::string>& Categories() const = 0;
    virtual std::size_t size() const = 0;
    /// Item i (0 <= i < size()); throws std::out_of_range, or std::runtime_error naming the file.
    virtual ShapeRecord Get(std::size_t i) const = 0;
};

/// Opens a dataset. `name_or_path`:
///   "cgal" (default embedded corpus), "procedural",
///   a ModelNet40 OFF tree (directory with <class>/{train,test}/*.off),
///   a ModelNet40 HDF5 directory (ply_data_{train,test}*.h5, or train_files.txt/test_files.txt),
///   a 7Scenes root (7-scenes-<scene>/*.ply, or a parent holding 7scene/),
///   an ICL-NUIM root (train/icl_nuim.h5, test/icl_nuim.h5, or a parent holding icl_nuim/),
///   a single .h5 file (datasets `points`, or `source`/`target`/`transform`, or `data`/`label`),
///   a single .ply / .pcd / .xyz / .off file, or a directory of such point files.
/// `split`: "all"; "train", "val", "test" (= "same_category/...");
/// "same_category/{train,val,test}"; "cross_category/{train,val,test}"; ModelNet40 also
/// "official/{train,test}". Datasets without categories to split (scans, point files) accept "all",
/// "train" and "test" where the layout defines them. Throws std::invalid_argument (unknown split)
/// or std::runtime_error naming the path.
std::unique_ptr<Dataset> OpenDataset(const std::string& name_or_path,
                                     const std::string& split = "all",
                                     const DatasetOptions& options = {});

/// The split `generate` uses when none is given: "all" for a point file or a folder of point
/// files (they have no splits), "test" otherwise. Throws like OpenDataset for a data root
/// holding several datasets.
std::string DefaultSplit(const std::string& name_or_path);

/// Refuses (std::invalid_argument naming it and listing the forms) a split name no dataset
/// has ("tset"): what `generate --split` checks before anything is read. Whether the dataset at
/// hand has that split is OpenDataset's to say.
void CheckSplitName(const std::string& split);

}  // namespace regbench
