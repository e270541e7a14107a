#include "datasets/point_file.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/coordinate_limit.hpp"
#include "core/parse_number.hpp"
#include "datasets/off_reader.hpp"

namespace regbench {
namespace {

std::string LowerExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

/// Registration libraries (PCL) convert to float and abort on overflow: refuse such clouds.
void CheckCoordinates(const std::string& path, const PointCloud& points) {
    for (Eigen::Index i = 0; i < points.rows(); ++i) {
        if (points.row(i).cwiseAbs().maxCoeff() > kMaxCoordinate) {
            throw std::runtime_error(path + ": point " + std::to_string(i) +
                                     " has a coordinate beyond the limit |x| <= 1e15 (does not "
                                     "fit in a float or in the methods' float arithmetic)");
        }
    }
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

/// What a PLY or PCD header promises, read by us before Open3D allocates anything.
struct DeclaredCloud {
    double points = 0;               ///< declared point count
    std::string points_text;         ///< the count as written in the header
    bool ascii = false;              ///< ASCII body (one point per line)
    bool compressed = false;         ///< PCD binary_compressed (LZF)
    double point_bytes = 0;          ///< bytes per point in a binary body (0: unknown)
    std::uintmax_t body_offset = 0;  ///< where the body starts
};

[[noreturn]] void HeaderError(const std::string& path, int line_no, const std::string& what) {
    throw std::runtime_error(path + ":" + std::to_string(line_no) + ": " + what);
}

/// Whole number from a header token, or an error naming the file and line (never std::stoul).
double HeaderCount(const std::string& path, int line_no, const std::string& token) {
    const auto v = ParseNumber<unsigned long long>(token);
    if (!v) HeaderError(path, line_no, "bad count '" + token + "' in header");
    return static_cast<double>(*v);
}

double PlyTypeBytes(const std::string& type) {
    if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
    if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
    if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" ||
        type == "float32")
        return 4;
    if (type == "double" || type == "float64") return 8;
    return 0;
}

/// Reads header lines (at most 1 MB of them) until `last` starts a line.
template <class OnLine>
std::uintmax_t ReadHeader(const std::string& path, const char* last, OnLine on_line) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error(path + ": cannot open point file");
    std::string line;
    int line_no = 0;
    while (std::getline(in, line)) {
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::istringstream words(line);
        std::vector<std::string> w;
        for (std::string t; words >> t;) w.push_back(t);
        on_line(line_no, w);
        if (!w.empty() && w[0] == last) return static_cast<std::uintmax_t>(in.tellg());
        if (in.tellg() > (1 << 20)) break;
    }
    throw std::runtime_error(path + ": header has no '" + std::string(last) +
                             "' line (truncated or not a point file)");
}

DeclaredCloud ReadPlyHeader(const std::string& path) {
    DeclaredCloud d;
    bool in_vertex = false;
    std::set<std::string> vertex_properties;  // a name twice: which one is x?
    d.body_offset = ReadHeader(path, "end_header", [&](int n, const std::vector<std::string>& w) {
        if (w.size() >= 2 && w[0] == "format") d.ascii = w[1] == "ascii";
        if (w.size() >= 3 && w[0] == "element") {
            in_vertex = w[1] == "vertex";
            if (in_vertex) {
                d.points = HeaderCount(path, n, w[2]);
                d.points_text = w[2];
            }
        }
        // A property line without type and name crashes Open3D's PLY reader (found by
        // fuzz_ply): refuse it here, before Open3D sees the file.
        if (!w.empty() && w[0] == "property" && w.size() < 3) {
            throw std::runtime_error(path + ":" + std::to_string(n) +
                                     ": PLY property line needs a type and a name");
        }
        if (in_vertex && w.size() >= 3 && w[0] == "property" &&
            !vertex_properties.insert(w.back()).second) {
            HeaderError(path, n, "PLY vertex property '" + w.back() + "' is declared twice");
        }
        if (in_vertex && w.size() >= 3 && w[0] == "property") {
            // A list takes at least its count (an empty list): the bytes per point are then a
            // lower bound, still enough to refuse 2e9 declared points in a tiny file (the
            // reader used to allocate for them first: a bare std::bad_alloc).
            d.point_bytes += PlyTypeBytes(w[1] == "list" ? w[2] : w[1]);
        }
    });
    return d;
}

// Every header line of a PCD file checked before Open3D's reader sees it (fuzzing found it
// crashing or allocating gigabytes on unchecked headers): one pass over the lines, one check
// per keyword, in the format's order.
DeclaredCloud ReadPcdHeader(const std::string& path) {
    DeclaredCloud d;
    std::vector<double> sizes, counts;
    std::size_t fields = 0, types = 0;
    int fields_line = 0;
    bool have_points = false;
    double width = -1, height = -1;  // -1: no such line
    int width_line = 0;
    d.body_offset = ReadHeader(path, "DATA", [&](int n, const std::vector<std::string>& w) {
        if (w.empty() || w[0][0] == '#') return;
        // Only the format's keywords: Open3D matches them by prefix, so a line "DATAH 3" ended
        // its header early and left its point count unset (fuzz_pcd: a 40 GB allocation).
        static const std::set<std::string> kKeywords = {
            "VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT",
            "POINTS",  "DATA"};
        if (kKeywords.count(w[0]) == 0) {
            HeaderError(path, n, "'" + w[0] + "' is no PCD header keyword");
        }
        if (w[0] == "FIELDS") {
            fields = w.size() - 1;
            fields_line = n;
            std::set<std::string> names;
            for (std::size_t i = 1; i < w.size(); ++i) {
                if (!names.insert(w[i]).second && w[i] != "_") {
                    HeaderError(path, n, "PCD field '" + w[i] + "' is declared twice");
                }
            }
        }
        if (w[0] == "WIDTH" && w.size() >= 2) {
            width = HeaderCount(path, n, w[1]);
            width_line = n;
        }
        if (w[0] == "HEIGHT" && w.size() >= 2) height = HeaderCount(path, n, w[1]);
        if (w[0] == "TYPE") {
            types = w.size() - 1;
            for (std::size_t i = 1; i < w.size(); ++i) {
                if (w[i] != "F" && w[i] != "I" && w[i] != "U") {
                    HeaderError(path, n, "PCD TYPE must be F, I or U, got '" + w[i] + "'");
                }
            }
        }
        if (w[0] == "POINTS" && w.size() >= 2) {
            d.points = HeaderCount(path, n, w[1]);
            d.points_text = w[1];
            have_points = true;
        }
        if (w[0] == "SIZE") {
            for (std::size_t i = 1; i < w.size(); ++i) {
                sizes.push_back(HeaderCount(path, n, w[i]));
                const double b = sizes.back();
                if (b != 1 && b != 2 && b != 4 && b != 8) {
                    HeaderError(path, n, "PCD SIZE must be 1, 2, 4 or 8, got '" + w[i] + "'");
                }
            }
        }
        // COUNT 0 (a field of no values) crashes Open3D's PCD reader (found by fuzz_pcd):
        // every field holds at least one value.
        if (w[0] == "COUNT") {
            for (std::size_t i = 1; i < w.size(); ++i) {
                counts.push_back(HeaderCount(path, n, w[i]));
                if (counts.back() < 1) {
                    HeaderError(path, n, "PCD COUNT must be at least 1, got '" + w[i] + "'");
                }
            }
        }
        if (w[0] == "DATA") {
            const std::string kind = w.size() >= 2 ? w[1] : "";
            if (kind != "ascii" && kind != "binary" && kind != "binary_compressed") {
                HeaderError(
                    path, n,
                    "PCD DATA must be ascii, binary or binary_compressed, got '" + kind + "'");
            }
            d.ascii = kind == "ascii";
            d.compressed = kind == "binary_compressed";
        }
    });
    // Open3D indexes SIZE, TYPE and COUNT by field: lists of another length than FIELDS are
    // refused here rather than read out of bounds there.
    if (fields == 0) throw std::runtime_error(path + ": PCD header has no FIELDS line");
    const auto same_length = [&](const char* key, std::size_t got, bool required) {
        if ((required || got > 0) && got != fields) {
            HeaderError(path, fields_line,
                        "PCD header lists " + std::to_string(fields) + " FIELDS but " +
                            std::to_string(got) + " " + key + " values");
        }
    };
    same_length("SIZE", sizes.size(), true);
    same_length("TYPE", types, true);
    same_length("COUNT", counts.size(), false);
    // Open3D takes the point count from POINTS only and reads garbage without one (fuzz_pcd: a
    // 33 GB allocation), so the line is required, as the PCD v0.7 format says.
    if (!have_points) throw std::runtime_error(path + ": PCD header has no POINTS line");
    // WIDTH x HEIGHT is the point count too; a header where they disagree is damaged, and
    // which count is meant cannot be told.
    if (width >= 0 && d.points != width * (height >= 0 ? height : 1.0)) {
        HeaderError(path, width_line,
                    "PCD WIDTH x HEIGHT (" + std::to_string(static_cast<long long>(width)) + " x " +
                        std::to_string(static_cast<long long>(height >= 0 ? height : 1.0)) +
                        ") does not match POINTS " + d.points_text);
    }
    for (std::size_t i = 0; i < sizes.size(); ++i) {
        d.point_bytes += sizes[i] * (i < counts.size() ? counts[i] : 1.0);
    }
    return d;
}

/// Refuses a header whose point count the file cannot hold, before any allocation. ASCII: a
/// point takes at least 6 bytes ("0 0 0\n") and one line; the lines are counted, so a
/// truncated ASCII body (which Open3D pads with zeros) is refused. Binary: count x point size
/// bytes must follow. LZF (PCD binary_compressed) expands at most ~100x.
void CheckDeclaredCloud(const std::string& path, const DeclaredCloud& d) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) throw std::runtime_error(path + ": cannot stat: " + ec.message());
    // A header whose end marker is the file's last bytes without a newline ends "past" the
    // file (found by fuzz_ply: the negative body size then overflowed a conversion).
    if (d.body_offset > size) {
        throw std::runtime_error(path +
                                 ": the header ends past the end of the file (truncated "
                                 "or corrupt file)");
    }
    const double body = static_cast<double>(size) - static_cast<double>(d.body_offset);
    const auto refuse = [&](const std::string& why) {
        // The count as written (a cast of 2^64-1 held in a double wrapped to 0).
        throw std::runtime_error(path + ": header declares " + d.points_text + " points but " +
                                 why + " (truncated or corrupt file)");
    };
    if (d.points < 1) throw std::runtime_error(path + ": header declares no points");
    if (d.ascii) {
        if (6.0 * d.points > body)
            refuse("only " + std::to_string(static_cast<long long>(body)) + " bytes follow");
        std::ifstream in(path, std::ios::binary);
        in.seekg(static_cast<std::streamoff>(d.body_offset));
        std::string line;
        double lines = 0;
        std::size_t line_no = 0;
        while (lines < d.points && std::getline(in, line)) {
            ++line_no;
            if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
            ++lines;
            // Every token of a point line is a number (nan and inf included: --nan-points
            // judges those); text there was read as zeros.
            std::istringstream words(line);
            for (std::string t; words >> t;) {
                if (!ParseNumber<double>(t)) {
                    throw std::runtime_error(path + ": body line " + std::to_string(line_no) +
                                             " after the header holds '" + t.substr(0, 40) +
                                             "', not a number (garbage or a damaged file)");
                }
            }
        }
        if (lines < d.points) {
            refuse("the body has only " + std::to_string(static_cast<long long>(lines)) +
                   " point lines");
        }
    } else if (d.point_bytes > 0) {
        const double need = d.points * d.point_bytes;
        if (d.compressed ? need > 100.0 * body : need > body) {
            refuse("only " + std::to_string(static_cast<long long>(body)) + " bytes follow");
        }
    }
}

}  // namespace

PointCloud ReadCloudFile(const std::string& path, NonFinitePoints non_finite) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".off") return ReadOff(path).vertices;
    return ReadPointFile(path, nullptr, non_finite);
}

PointCloud ReadPointFile(const std::string& path, Normals* normals, NonFinitePoints non_finite) {
    if (!std::filesystem::is_regular_file(path)) {
        throw std::runtime_error(path + ": no such point file");
    }
    const std::string ext = LowerExtension(path);
    if (ext == ".xyz" || ext == ".xyzn" || ext == ".txt") {
        PointCloud points = ReadXyz(path, normals);
        CheckCoordinates(path, points);
        return points;
    }
    if (ext == ".ply" || ext == ".pcd") {
        const DeclaredCloud declared = ext == ".ply" ? ReadPlyHeader(path) : ReadPcdHeader(path);
        CheckDeclaredCloud(path, declared);
        PointCloud points = ReadPointFileOpen3D(path, normals, non_finite);
        if (static_cast<double>(points.rows()) > declared.points) {
            throw std::runtime_error(path + ": " + std::to_string(points.rows()) +
                                     " points read but the header declares " +
                                     std::to_string(static_cast<long long>(declared.points)));
        }
        CheckCoordinates(path, points);
        return points;
    }
    throw std::runtime_error(path + ": unsupported point file type '" + ext +
                             "' (expected .ply, .pcd, .xyz, .xyzn or .txt)");
}

}  // namespace regbench
