// The pieces every dataset loader shares (datasets/dataset_impl.hpp): split parsing, the
// official-split rule, the data folder and the list-backed Dataset. Kept apart from
// dataset.cpp (layout detection) and dataset_hdf5.cpp (HDF5 layouts), which both call into
// it, so the loaders form no call circle: dataset.cpp -> dataset_hdf5.cpp -> dataset_list.cpp.
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/data_dir.hpp"
#include "datasets/dataset_impl.hpp"

namespace regbench {
namespace fs = std::filesystem;

namespace detail {

SplitSpec ParseSplit(const std::string& split) {
    SplitSpec s;
    s.text = split;
    const auto slash = split.find('/');
    if (slash == std::string::npos) {
        if (split == "all") {
            s.protocol = "all";
        } else {
            s.protocol = "same_category";
            s.part = split;
        }
    } else {
        s.protocol = split.substr(0, slash);
        s.part = split.substr(slash + 1);
    }
    const bool ok_protocol = s.protocol == "all" || s.protocol == "same_category" ||
                             s.protocol == "cross_category" || s.protocol == "official";
    const bool ok_part = s.protocol == "all" ? s.part.empty()
                         : s.protocol == "official"
                             ? (s.part == "train" || s.part == "test")
                             : (s.part == "train" || s.part == "val" || s.part == "test");
    if (!ok_protocol || !ok_part) {
        throw std::invalid_argument(
            "dataset split '" + split +
            "': expected all, train, val, test, same_category/{train,val,test}, "
            "cross_category/{train,val,test} or official/{train,test}");
    }
    return s;
}

bool InOfficialSplit(const SplitSpec& split, int label, int num_labels, bool official_test,
                     std::size_t rank) {
    constexpr std::size_t kValEvery = 5;  // 80/20 train/validation (docs/datasets.md)
    if (split.protocol == "all") return true;
    if (split.protocol == "official") return official_test == (split.part == "test");
    const bool first_half = label < num_labels / 2;
    if (split.part == "test") {
        return official_test && (split.protocol == "same_category" ? first_half : !first_half);
    }
    if (!first_half || official_test) return false;
    const bool is_val = rank % kValEvery == kValEvery - 1;
    return split.part == "val" ? is_val : !is_val;
}

namespace {

class ListDataset : public Dataset {
public:
    ListDataset(std::string kind, std::string split, std::vector<std::string> categories,
                std::vector<Entry> entries, EntryLoader loader)
        : kind_(std::move(kind)),
          split_(std::move(split)),
          categories_(std::move(categories)),
          entries_(std::move(entries)),
          loader_(std::move(loader)) {}
    std::string Kind() const override { return kind_; }
    std::string Split() const override { return split_; }
    const std::vector<std::string>& Categories() const override { return categories_; }
    std::size_t size() const override { return entries_.size(); }
    ShapeRecord Get(std::size_t i) const override {
        if (i >= entries_.size()) {
            throw std::out_of_range(kind_ + " dataset: index " + std::to_string(i) +
                                    " out of range (size " + std::to_string(entries_.size()) + ")");
        }
        const Entry& e = entries_[i];
        ShapeRecord record = loader_(e);
        record.name = e.name;
        record.category = e.category;
        record.label = e.label;
        record.file = e.file;
        return record;
    }

private:
    std::string kind_, split_;
    std::vector<std::string> categories_;
    std::vector<Entry> entries_;
    EntryLoader loader_;
};

}  // namespace

std::unique_ptr<Dataset> MakeListDataset(std::string kind, std::string split,
                                         std::vector<std::string> categories,
                                         std::vector<Entry> entries, EntryLoader loader) {
    return std::make_unique<ListDataset>(std::move(kind), std::move(split), std::move(categories),
                                         std::move(entries), std::move(loader));
}

std::string DataDir(const DatasetOptions& options) {
    return options.data_dir.empty() ? regbench::DataDir() : options.data_dir;
}

}  // namespace detail

}  // namespace regbench
