#include "protocols/xyz_io.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <regex>
#include <stdexcept>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/coordinate_limit.hpp"
#include "core/input_file.hpp"
#include "core/transform.hpp"
#include "protocols/pair_protocols.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;

/// Tolerance on |R^T R - I| and |det R - 1| for an imported ground truth (text round-off).
constexpr double kRotationTolerance = 1e-6;
/// Largest pair number an import accepts (pairs must be numbered 0, 1, 2, ... anyway).
constexpr std::size_t kMaxImportPairs = 100000000;

[[noreturn]] void FailAt(const std::string& path, std::size_t line, const std::string& what) {
    throw std::runtime_error(path + ":" + std::to_string(line) + ": " + what);
}

/// Parses the whitespace-separated numbers of one line (locale-independent from_chars).
std::vector<double> ParseNumbers(const std::string& path, std::size_t line_no,
                                 const std::string& line) {
    std::vector<double> values;
    const char* p = line.data();
    const char* end = line.data() + line.size();
    while (true) {
        while (p < end && std::isspace(static_cast<unsigned char>(*p))) ++p;
        if (p == end) break;
        double v = 0.0;
        const auto [next, ec] = std::from_chars(p, end, v);
        const char* token_end = p;
        while (token_end < end && !std::isspace(static_cast<unsigned char>(*token_end)))
            ++token_end;
        if (ec != std::errc() || next != token_end) {
            FailAt(path, line_no, "not a number: '" + std::string(p, token_end) + "'");
        }
        if (!std::isfinite(v)) FailAt(path, line_no, "non-finite value");
        // Registration libraries (PCL) work in float and abort on overflow: one limit,
        // kMaxCoordinate (core/point_cloud.hpp).
        if (std::abs(v) > kMaxCoordinate) {
            FailAt(path, line_no,
                   "value " + std::string(p, token_end) +
                       " is beyond the coordinate limit |x| <= 1e15 (does not fit in a float or "
                       "in the methods' float arithmetic)");
        }
        values.push_back(v);
        p = next;
    }
    return values;
}

bool SkipLine(const std::string& line) {
    const auto first = line.find_first_not_of(" \t\r");
    return first == std::string::npos || line[first] == '#';
}

std::ifstream OpenText(const std::string& path) {
    RequireRegularFile(path);
    std::ifstream in(path);
    if (!in) throw std::runtime_error(path + ": cannot open");
    return in;
}

/// Checked write of one exported file (inside the export's temporary directory).
void WriteTextFile(const std::string& path, const std::string& text) {
    WriteFileAtomic(path, text);
}

std::string FormatRow(double a, double b, double c) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "%.17g %.17g %.17g\n", a, b, c);
    return buf;
}

std::string XyzText(const PointCloud& cloud) {
    std::string text;
    for (Eigen::Index i = 0; i < cloud.rows(); ++i)
        text += FormatRow(cloud(i, 0), cloud(i, 1), cloud(i, 2));
    return text;
}

std::string PlyText(const PointCloud& cloud) {
    std::string text = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(cloud.rows()) +
                       "\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
    return text + XyzText(cloud);
}

std::string TransformText(const Transform& T) {
    std::string text;
    char buf[128];
    for (int r = 0; r < 4; ++r) {
        std::snprintf(buf, sizeof(buf), "%.17g %.17g %.17g %.17g\n", T(r, 0), T(r, 1), T(r, 2),
                      T(r, 3));
        text += buf;
    }
    return text;
}

/// An export goes to a fresh temporary directory next to `dir` and is renamed into place only
/// when every file was written, so `dir` never holds a partial export or stale pairs of an
/// earlier one (which `import` would pick up). `dir` must be absent or empty.
class ExportDir {
public:
    explicit ExportDir(const std::string& dir) : dir_(dir) {
        // "out/" is the folder "out": without this its temporary went inside it (parent_path of
        // "out/" is "out"), and the rename over the then non-empty folder failed.
        while (dir_.size() > 1 && dir_.back() == '/') dir_.pop_back();
        std::error_code ec;
        if (fs::exists(dir_, ec)) {
            if (!fs::is_directory(dir_))
                throw std::runtime_error(dir_ + ": exists and is not a directory");
            if (!fs::is_empty(dir_)) {
                throw std::runtime_error(dir_ +
                                         ": directory is not empty (export refuses to mix "
                                         "with earlier files; remove it or pick another)");
            }
        }
        const fs::path parent =
            fs::path(dir_).parent_path().empty() ? fs::path(".") : fs::path(dir_).parent_path();
        fs::create_directories(parent, ec);
        std::string templ =
            (parent / ("." + fs::path(dir_).filename().string() + ".tmp.XXXXXX")).string();
        if (::mkdtemp(templ.data()) == nullptr) {
            throw std::runtime_error(dir_ + ": cannot create a temporary directory");
        }
        temp_ = templ;
    }
    ~ExportDir() {
        std::error_code ec;
        if (!temp_.empty()) fs::remove_all(temp_, ec);
    }
    std::string File(const std::string& name) const { return (fs::path(temp_) / name).string(); }
    /// Renames the finished export over `dir` (rename(2) replaces an empty directory).
    void Commit() {
        ::chmod(temp_.c_str(), 0755);
        if (::rename(temp_.c_str(), dir_.c_str()) != 0) {
            throw std::runtime_error(
                dir_ + ": cannot move the export into place: " + std::strerror(errno));
        }
        temp_.clear();
    }

private:
    std::string dir_;
    std::string temp_;
};

}  // namespace

PointCloud ReadXyz(const std::string& path) {
    std::ifstream in = OpenText(path);
    std::vector<double> values;
    std::string line;
    std::size_t line_no = 0;
    while (std::getline(in, line)) {
        ++line_no;
        if (SkipLine(line)) continue;
        const std::vector<double> v = ParseNumbers(path, line_no, line);
        if (v.size() != 3) {
            FailAt(path, line_no, "expected 3 numbers 'x y z', got " + std::to_string(v.size()));
        }
        values.insert(values.end(), v.begin(), v.end());
    }
    if (values.empty()) throw std::runtime_error(path + ": no points");
    PointCloud cloud(static_cast<Eigen::Index>(values.size() / 3), 3);
    std::copy(values.begin(), values.end(), cloud.data());
    return cloud;
}

Transform ReadTransformTxt(const std::string& path) {
    std::ifstream in = OpenText(path);
    Transform T = Transform::Zero();
    int row = 0;
    std::string line;
    std::size_t line_no = 0;
    std::size_t last_row_line = 0;
    while (std::getline(in, line)) {
        ++line_no;
        if (SkipLine(line)) continue;
        const std::vector<double> v = ParseNumbers(path, line_no, line);
        if (row == 4) FailAt(path, line_no, "more than 4 rows (expected a 4 x 4 matrix)");
        if (v.size() != 4) {
            FailAt(path, line_no, "expected 4 numbers per row, got " + std::to_string(v.size()));
        }
        for (int c = 0; c < 4; ++c) T(row, c) = v[static_cast<std::size_t>(c)];
        ++row;
        last_row_line = line_no;
    }
    if (row != 4) {
        FailAt(path, line_no, "expected 4 rows of a 4 x 4 matrix, got " + std::to_string(row));
    }
    if ((T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > kRotationTolerance) {
        FailAt(path, last_row_line, "last row must be 0 0 0 1");
    }
    T.row(3) << 0, 0, 0, 1;
    if (!IsRotation(T.topLeftCorner<3, 3>(), kRotationTolerance)) {
        throw std::runtime_error(path + ": rows 1-3: the 3 x 3 block is not a rotation");
    }
    return T;
}

std::string PairStem(std::size_t k) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%04zu", k);
    return buf;
}

namespace {

/// Writes pair k as <stem>_src.<ext> and <stem>_tgt.<ext> (the clouds as `cloud_text` writes
/// them) and <stem>_gt.txt into `dir`, committed together at the end.
void ExportPairs(const PairSet& set, const std::string& dir, const std::string& ext,
                 std::string (*cloud_text)(const PointCloud&)) {
    ExportDir out(dir);
    for (std::size_t k = 0; k < set.pairs.size(); ++k) {
        const std::string stem = PairStem(k);
        WriteTextFile(out.File(stem + "_src." + ext), cloud_text(set.pairs[k].source));
        WriteTextFile(out.File(stem + "_tgt." + ext), cloud_text(set.pairs[k].target));
        WriteTextFile(out.File(stem + "_gt.txt"), TransformText(set.pairs[k].T_gt));
    }
    out.Commit();
}

}  // namespace

void ExportXyz(const PairSet& set, const std::string& dir) {
    ExportPairs(set, dir, "xyz", XyzText);
}

void ExportPly(const PairSet& set, const std::string& dir) {
    ExportPairs(set, dir, "ply", PlyText);
}

PairSet ImportXyzDir(const std::string& dir, double eta) {
    if (!fs::is_directory(dir)) throw std::runtime_error(dir + ": not a directory");
    if (!(eta > 0.0)) throw std::invalid_argument("import: eta must be > 0");
    // Collect the pair numbers present, from any of the three file kinds.
    const std::regex pattern(R"((\d+)_(src\.xyz|tgt\.xyz|gt\.txt))");
    std::map<std::size_t, int> seen;
    // (number, kind) -> the file name that gave it: 0001_src.xyz and 00001_src.xyz are the same
    // pair and file kind spelled twice; one would be read and the other ignored silently.
    std::map<std::pair<std::size_t, std::string>, std::string> spelled;
    for (const auto& entry : fs::directory_iterator(dir)) {
        std::smatch m;
        const std::string name = entry.path().filename().string();
        if (!std::regex_match(name, m, pattern)) continue;
        std::size_t number = 0;
        const std::string digits = m[1].str();
        const auto [end, ec] =
            std::from_chars(digits.data(), digits.data() + digits.size(), number);
        if (ec != std::errc() || end != digits.data() + digits.size() || number > kMaxImportPairs) {
            throw std::runtime_error(entry.path().string() + ": pair number " + digits +
                                     " is out of range");
        }
        const auto [it, fresh] = spelled.emplace(std::make_pair(number, m[2].str()), name);
        if (!fresh) {
            const auto [first, second] = std::minmax(it->second, name);
            throw std::runtime_error(dir + ": " + first + " and " + second + " both name pair " +
                                     std::to_string(number) + " (ambiguous; keep one)");
        }
        seen[number] += 1;
    }
    if (seen.empty()) {
        throw std::runtime_error(dir + ": no NNNN_src.xyz / NNNN_tgt.xyz / NNNN_gt.txt files");
    }
    PairSet set;
    std::size_t k = 0;
    for (const auto& [number, count] : seen) {
        (void)count;
        const std::string stem = (fs::path(dir) / PairStem(k)).string();
        if (number != k)
            throw std::runtime_error(stem +
                                     "_src.xyz: missing (pairs must be numbered 0, 1, 2, ...)");
        Pair pair;
        pair.source = ReadXyz(stem + "_src.xyz");
        pair.target = ReadXyz(stem + "_tgt.xyz");
        pair.T_gt = ReadTransformTxt(stem + "_gt.txt");
        pair.shape = PairStem(k);
        LabelOverlapByRadius(pair, eta);
        set.pairs.push_back(std::move(pair));
        ++k;
    }
    set.provenance = {{"protocol", "imported"},
                      {"format", "xyz"},
                      {"overlap_labels", "radius"},
                      {"params", {{"eta", eta}}},
                      {"num_pairs", set.pairs.size()}};
    return set;
}

std::string TwoCloudPlyText(const PointCloud& source, const PointCloud& target) {
    std::string text = "ply\nformat ascii 1.0\nelement vertex " +
                       std::to_string(source.rows() + target.rows()) +
                       "\nproperty double x\nproperty double y\nproperty double z\n"
                       "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                       "end_header\n";
    char buf[128];
    for (const auto& [cloud, rgb] :
         {std::pair{&source, "255 128 0"}, std::pair{&target, "0 102 255"}}) {
        for (Eigen::Index i = 0; i < cloud->rows(); ++i) {
            std::snprintf(buf, sizeof(buf), "%.17g %.17g %.17g %s\n", (*cloud)(i, 0),
                          (*cloud)(i, 1), (*cloud)(i, 2), rgb);
            text += buf;
        }
    }
    return text;
}

}  // namespace regbench
