#pragma once
// Internals shared by the dataset loaders (dataset*.cpp); not part of the public interface.
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "datasets/dataset.hpp"

namespace regbench::detail {

/// A split name taken apart: protocol "all", "same_category", "cross_category" or "official";
/// part "", "train", "val" or "test".
struct SplitSpec {
    std::string protocol;
    std::string part;
    std::string text;  ///< as given, for messages
};

/// Parses "all", "train" | "val" | "test" (same_category), "<protocol>/<part>".
/// Throws std::invalid_argument naming the split.
SplitSpec ParseSplit(const std::string& split);

/// Membership rule for datasets with an official train/test division and category labels
/// (ModelNet40): categories [0, num_labels / 2) form the "first half". same_category uses the
/// first half only: train/val = official train with every 5th item of a category (rank % 5 == 4)
/// held out as val; test = official test. cross_category: train/val as same_category, test =
/// official test of the second half. `rank` counts the item within its category's official
/// train items (file order).
bool InOfficialSplit(const SplitSpec& split, int label, int num_labels, bool official_test,
                     std::size_t rank);

/// One item before loading.
struct Entry {
    std::string name;
    std::string category;
    int label = -1;
    std::string file;
    std::size_t index = 0;  ///< item within `file` (HDF5 rows), else 0
};

using EntryLoader = std::function<ShapeRecord(const Entry&)>;

/// A dataset that is a list of entries plus a loader (which must be safe to call concurrently).
/// The data folder for named datasets: options.data_dir, else regbench::DataDir()
/// (core/data_dir.hpp).
std::string DataDir(const DatasetOptions& options);

std::unique_ptr<Dataset> MakeListDataset(std::string kind, std::string split,
                                         std::vector<std::string> categories,
                                         std::vector<Entry> entries, EntryLoader loader);

/// HDF5-backed datasets (dataset_hdf5.cpp).
bool LooksLikeModelNetH5Dir(const std::string& dir);
std::unique_ptr<Dataset> OpenModelNetH5(const std::string& dir, const SplitSpec& split);
bool LooksLikeIclNuimDir(const std::string& dir);
std::unique_ptr<Dataset> OpenIclNuim(const std::string& dir, const SplitSpec& split);
/// One .h5 file with `data` (+ `label`, `normal`), or `points`, or `source`/`target`/`transform`.
std::unique_ptr<Dataset> OpenPointsH5(const std::string& path, const SplitSpec& split);

}  // namespace regbench::detail
