#pragma once
// The one owner of an HDF5 identifier, shared by the pair files (protocols/pair_file.cpp) and
// the HDF5 datasets (datasets/dataset_hdf5.cpp). Callers link HDF5 themselves.
#include <hdf5.h>

namespace regbench {

/// Owns one HDF5 identifier (file, group, dataset, dataspace, type, property list, attribute)
/// and closes it with the matching H5?close function. A negative id means "failed to open".
class H5Handle {
public:
    H5Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
    ~H5Handle() {
        if (id_ >= 0) close_(id_);
    }
    H5Handle(const H5Handle&) = delete;
    H5Handle& operator=(const H5Handle&) = delete;
    H5Handle(H5Handle&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
    H5Handle& operator=(H5Handle&&) = delete;
    hid_t get() const { return id_; }
    bool ok() const { return id_ >= 0; }

private:
    hid_t id_;
    herr_t (*close_)(hid_t);
};

}  // namespace regbench
