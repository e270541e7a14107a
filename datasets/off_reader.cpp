#include "datasets/off_reader.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/input_file.hpp"

namespace regbench {
namespace {

/// Reads the next line that is not blank after stripping a '#' comment; false at end of file.
bool NextDataLine(std::istream& in, std::string& line, int& line_no) {
    while (std::getline(in, line)) {
        ++line_no;
        const auto hash = line.find('#');
        if (hash != std::string::npos) line.erase(hash);
        if (line.find_first_not_of(" \t\r\n\f\v") != std::string::npos) return true;
    }
    return false;
}

std::string Where(const std::string& path, int line_no) {
    return path + ":" + std::to_string(line_no) + ": ";
}

/// Parses every whitespace-separated number on `text`; throws on a non-numeric token.
std::vector<double> ParseNumbers(const std::string& text, const std::string& path, int line_no) {
    std::vector<double> values;
    const char* p = text.c_str();
    while (true) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n' || *p == '\f' || *p == '\v') ++p;
        if (*p == '\0') break;
        char* end = nullptr;
        errno = 0;
        const double v = std::strtod(p, &end);
        if (end == p || errno == ERANGE || !std::isfinite(v)) {
            throw std::runtime_error(Where(path, line_no) + "OFF: not a number near '" +
                                     std::string(p).substr(0, 16) + "'");
        }
        values.push_back(v);
        p = end;
    }
    return values;
}

int ToCount(double v, const std::string& what, const std::string& path, int line_no) {
    if (v < 0.0 || v != std::floor(v) || v > 2.0e9) {
        throw std::runtime_error(Where(path, line_no) + "OFF: invalid " + what + " " +
                                 std::to_string(v));
    }
    return static_cast<int>(v);
}

/// Splits the header line into its keyword and whatever follows it on the same line (the
/// counts, in ModelNet40's malformed "OFF490 1000 0" or in "OFF 8 6 0").
void ParseHeader(const std::string& line, const std::string& path, int line_no, std::string& rest) {
    const auto begin = line.find_first_not_of(" \t");
    const auto pos = line.find("OFF", begin);
    if (pos == std::string::npos) {
        throw std::runtime_error(Where(path, line_no) + "not an OFF file (header '" + line + "')");
    }
    const std::string prefix = line.substr(begin, pos - begin);
    // Accepted prefixes: ST, C, N, 4 is not (4D), n is not (nD); OFF BINARY is not supported.
    for (char c : prefix) {
        if (c != 'S' && c != 'T' && c != 'C' && c != 'N') {
            throw std::runtime_error(Where(path, line_no) + "unsupported OFF variant '" + prefix +
                                     "OFF'");
        }
    }
    rest = line.substr(pos + 3);
    if (rest.find("BINARY") != std::string::npos) {
        throw std::runtime_error(Where(path, line_no) + "binary OFF is not supported");
    }
}

/// The `num_faces` face lines of an OFF file, fan-triangulated; indices checked against
/// num_vertices. line_no tracks the current line for error messages.
std::vector<Eigen::Vector3i> ReadOffFaces(std::istream& in, const std::string& path, int& line_no,
                                          int num_vertices, int num_faces) {
    std::string line;
    std::vector<Eigen::Vector3i> triangles;
    triangles.reserve(static_cast<std::size_t>(num_faces));
    for (int f = 0; f < num_faces; ++f) {
        if (!NextDataLine(in, line, line_no)) {
            throw std::runtime_error(path + ": truncated OFF file: " + std::to_string(f) + " of " +
                                     std::to_string(num_faces) + " faces");
        }
        const std::vector<double> v = ParseNumbers(line, path, line_no);
        const int n = v.empty() ? 0 : ToCount(v[0], "face size", path, line_no);
        if (n < 3 || static_cast<int>(v.size()) < n + 1) {
            throw std::runtime_error(Where(path, line_no) + "OFF: malformed face (size " +
                                     std::to_string(n) + ", " + std::to_string(v.size() - 1) +
                                     " indices)");
        }
        std::vector<int> idx(static_cast<std::size_t>(n));
        for (int k = 0; k < n; ++k) {
            const double x = v[static_cast<std::size_t>(k) + 1];
            if (x < 0.0 || x >= num_vertices || x != std::floor(x)) {
                throw std::runtime_error(Where(path, line_no) + "OFF: vertex index " +
                                         std::to_string(x) + " out of range [0, " +
                                         std::to_string(num_vertices) + ")");
            }
            idx[static_cast<std::size_t>(k)] = static_cast<int>(x);
        }
        // Fan triangulation (v0, vk, vk+1); values after the indices (colours) are ignored.
        for (int k = 1; k + 1 < n; ++k) {
            triangles.emplace_back(idx[0], idx[static_cast<std::size_t>(k)],
                                   idx[static_cast<std::size_t>(k) + 1]);
        }
    }
    return triangles;
}

}  // namespace

// OFF and its variants in one pass over the file (header keyword, counts, vertices, faces),
// each step refusing bad input with the file and line: long because every field is checked.
Mesh ReadOff(const std::string& path) {
    RequireRegularFile(path);
    std::ifstream in(path);
    if (!in) throw std::runtime_error(path + ": cannot open OFF file");
    std::string line;
    int line_no = 0;
    if (!NextDataLine(in, line, line_no)) throw std::runtime_error(path + ": empty OFF file");
    std::string counts_text;
    ParseHeader(line, path, line_no, counts_text);
    if (counts_text.find_first_not_of(" \t\r") == std::string::npos) {
        if (!NextDataLine(in, counts_text, line_no)) {
            throw std::runtime_error(path + ": truncated OFF file (no vertex/face counts)");
        }
    }
    const std::vector<double> counts = ParseNumbers(counts_text, path, line_no);
    if (counts.size() < 2) {
        throw std::runtime_error(Where(path, line_no) + "OFF: expected 'vertices faces [edges]'");
    }
    const int num_vertices = ToCount(counts[0], "vertex count", path, line_no);
    const int num_faces = ToCount(counts[1], "face count", path, line_no);

    // Bound the allocations by the file: a vertex line takes at least 6 bytes ("0 0 0\n"), a
    // face line at least 8 ("3 0 1 2\n"); a header declaring more is truncated or hostile.
    std::error_code size_ec;
    const double file_bytes = static_cast<double>(std::filesystem::file_size(path, size_ec));
    if (!size_ec && 6.0 * num_vertices + 8.0 * num_faces > file_bytes) {
        throw std::runtime_error(Where(path, line_no) + "OFF: header declares " +
                                 std::to_string(num_vertices) + " vertices and " +
                                 std::to_string(num_faces) + " faces, more than the file's " +
                                 std::to_string(static_cast<long long>(file_bytes)) +
                                 " bytes can hold (truncated or corrupt)");
    }
    Mesh mesh;
    mesh.vertices.resize(num_vertices, 3);
    for (int i = 0; i < num_vertices; ++i) {
        if (!NextDataLine(in, line, line_no)) {
            throw std::runtime_error(path + ": truncated OFF file: " + std::to_string(i) + " of " +
                                     std::to_string(num_vertices) + " vertices");
        }
        // x y z, then optional normal / colour / texture values, which are ignored.
        const std::vector<double> v = ParseNumbers(line, path, line_no);
        if (v.size() < 3) {
            throw std::runtime_error(Where(path, line_no) + "OFF: vertex with fewer than 3 values");
        }
        for (int c = 0; c < 3; ++c) {
            if (!std::isfinite(v[c]) ||
                std::abs(v[c]) > static_cast<double>(std::numeric_limits<float>::max())) {
                throw std::runtime_error(Where(path, line_no) +
                                         "OFF: vertex coordinate is not finite or does not fit "
                                         "in a float");
            }
        }
        mesh.vertices.row(i) << v[0], v[1], v[2];
    }

    const std::vector<Eigen::Vector3i> triangles =
        ReadOffFaces(in, path, line_no, num_vertices, num_faces);
    mesh.faces.resize(static_cast<Eigen::Index>(triangles.size()), 3);
    for (std::size_t t = 0; t < triangles.size(); ++t) {
        mesh.faces.row(static_cast<Eigen::Index>(t)) = triangles[t].transpose();
    }
    return mesh;
}

}  // namespace regbench
