#pragma once
// Helpers for protocol tests: fresh temporary folders, small text and HDF5 files.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/testing/expect_throw.hpp"  // ExpectThrowsWith, used with these files

namespace regbench::testing {

/// An empty folder under the test temp dir, named after the running test.
inline std::filesystem::path FreshDir(const std::string& tag = "") {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const std::filesystem::path dir =
        std::filesystem::path(::testing::TempDir()) /
        ("regbench_" + std::string(info->test_suite_name()) + "_" + info->name() + tag);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

inline std::string WriteText(const std::filesystem::path& path, const std::string& text) {
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path) << text;
    return path.string();
}

/// One dataset to write: shape, values (converted from double by HDF5) and the file type.
struct H5Dataset {
    std::string name;
    std::vector<hsize_t> dims;
    std::vector<double> values;
    hid_t file_type = H5T_IEEE_F32LE;
};

inline std::string WriteH5(const std::filesystem::path& path, const std::vector<H5Dataset>& sets) {
    std::filesystem::create_directories(path.parent_path());
    const hid_t file = H5Fcreate(path.string().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (file < 0) throw std::runtime_error("cannot create " + path.string());
    for (const H5Dataset& d : sets) {
        const hid_t space =
            H5Screate_simple(static_cast<int>(d.dims.size()), d.dims.data(), nullptr);
        const hid_t ds = H5Dcreate2(file, d.name.c_str(), d.file_type, space, H5P_DEFAULT,
                                    H5P_DEFAULT, H5P_DEFAULT);
        // No values: the dataset keeps only its declared shape (storage allocated late).
        if (!d.values.empty()) {
            H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, d.values.data());
        }
        H5Dclose(ds);
        H5Sclose(space);
    }
    H5Fclose(file);
    return path.string();
}

/// A tetrahedron in OFF format (optionally with ModelNet40's run-together header).
inline std::string TetraOff(double scale = 1.0, bool modelnet_header = false) {
    const std::string s = std::to_string(scale);
    return std::string(modelnet_header ? "OFF4 4 0\n" : "OFF\n4 4 0\n") + "0 0 0\n" + s +
           " 0 0\n0 " + s + " 0\n0 0 " + s + "\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
}

}  // namespace regbench::testing
