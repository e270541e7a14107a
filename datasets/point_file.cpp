#include "datasets/point_file.hpp"

#include "datasets/off_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace regbench {
namespace {

std::string LowerExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

/// Plain-text XYZ: "x y z [nx ny nz ...]" per line. Normals are kept only when every point
/// line carries at least six numbers.
PointCloud ReadXyz(const std::string& path, Normals* normals) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error(path + ": cannot open point file");
    std::vector<double> xyz, nrm;
    bool all_have_normals = true;
    std::string line;
    int line_no = 0;
    while (std::getline(in, line)) {
        ++line_no;
        const auto hash = line.find('#');
        if (hash != std::string::npos) line.erase(hash);
        double v[6];
        int count = 0;
        const char* p = line.c_str();
        while (true) {
            while (*p != '\0' && std::isspace(static_cast<unsigned char>(*p))) ++p;
            if (*p == '\0') break;
            char* end = nullptr;
            errno = 0;
            const double x = std::strtod(p, &end);
            // Commas are accepted as separators ("x,y,z" exports).
            if (end == p || errno == ERANGE || !std::isfinite(x) ||
                (*end != '\0' && *end != ',' && !std::isspace(static_cast<unsigned char>(*end)))) {
                throw std::runtime_error(path + ":" + std::to_string(line_no) +
                                         ": not a number in XYZ line '" + line + "'");
            }
            if (count < 6) v[count] = x;
            ++count;
            p = (*end == ',') ? end + 1 : end;
        }
        if (count == 0) continue;
        if (count < 3) {
            throw std::runtime_error(path + ":" + std::to_string(line_no) +
                                     ": XYZ line has fewer than 3 numbers");
        }
        xyz.insert(xyz.end(), v, v + 3);
        if (count >= 6) {
            nrm.insert(nrm.end(), v + 3, v + 6);
        } else {
            all_have_normals = false;
        }
    }
    if (xyz.empty()) throw std::runtime_error(path + ": XYZ file has no points");
    const Eigen::Index n = static_cast<Eigen::Index>(xyz.size() / 3);
    PointCloud points = Eigen::Map<const PointCloud>(xyz.data(), n, 3);
    if (normals != nullptr) {
        normals->resize(0, 3);
        if (all_have_normals) *normals = Eigen::Map<const Normals>(nrm.data(), n, 3);
    }
    return points;
}

}  // namespace

PointCloud ReadCloudFile(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".off") return ReadOff(path).vertices;
    return ReadPointFile(path);
}

PointCloud ReadPointFile(const std::string& path, Normals* normals) {
    if (!std::filesystem::is_regular_file(path)) {
        throw std::runtime_error(path + ": no such point file");
    }
    const std::string ext = LowerExtension(path);
    if (ext == ".xyz" || ext == ".xyzn" || ext == ".txt") return ReadXyz(path, normals);
    if (ext == ".ply" || ext == ".pcd") return ReadPointFileOpen3D(path, normals);
    throw std::runtime_error(path + ": unsupported point file type '" + ext +
                             "' (expected .ply, .pcd, .xyz, .xyzn or .txt)");
}

}  // namespace regbench
