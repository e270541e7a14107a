#pragma once
// The same clouds at unit scale and in millimetres (issue 54 item 1's acceptance): a folder of
// point files, its copy times 150, the pair files `generate` (`--scale 150` for the copy) makes
// of them, the rows `run` writes on each and the per-method comparison of the two.
//
// Expected relations, derived by hand: the copy maps every point x to s x (s = 150), so a pair
// (P, Q) with ground truth (R, t) becomes (s P, s Q) with ground truth (R, s t) (a similarity
// preserves angles). A method whose every length scales with the data returns (R', s t') on the
// copy when it returns (R', t') on the unit pair; then mae_r and rre are the same, mae_t, rte and
// the CCD (clip times s) are s times the unit values, and recall and success with thresholds
// times s accept the same pairs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "runners/result_row.hpp"
#include "tests/testing/cli.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/shapes.hpp"

namespace regbench::testing {

constexpr double kMillimetres = 150.0;

/// Writes `shapes` lumpy ellipsoids (1024 points, seeds 1..shapes) as DIR/unit/*.xyz and the
/// same times 150 as DIR/mm/*.xyz, generates `pairs` partial pairs of each (seed 1; the mm ones
/// with --scale 150) and runs `methods` on both (one job, one thread).
inline void RunUnitAndMillimetres(const std::filesystem::path& dir, int shapes, int pairs,
                                  const std::string& methods) {
    for (const char* unit : {"unit", "mm"}) std::filesystem::create_directories(dir / unit);
    for (int k = 1; k <= shapes; ++k) {
        const PointCloud P = LumpyEllipsoid(1024, static_cast<std::uint64_t>(k));
        for (const char* unit : {"unit", "mm"}) {
            const double s = std::string(unit) == "mm" ? kMillimetres : 1.0;
            const std::string path = (dir / unit / ("shape" + std::to_string(k) + ".xyz")).string();
            std::FILE* f = std::fopen(path.c_str(), "w");
            ASSERT_NE(f, nullptr) << path;
            for (Eigen::Index i = 0; i < P.rows(); ++i) {
                std::fprintf(f, "%.17g %.17g %.17g\n", s * P(i, 0), s * P(i, 1), s * P(i, 2));
            }
            std::fclose(f);
        }
    }
    for (const char* unit : {"unit", "mm"}) {
        const std::string d = (dir / unit).string();
        RunCliOk("generate --dataset " + d + " --pairs " + std::to_string(pairs) +
                 " --seed 1 --out " + d + ".h5" +
                 (std::string(unit) == "mm" ? " --scale 150" : ""));
        RunCliOk("run --pairs " + d + ".h5 --methods " + methods +
                 " --jobs 1 --threads 1 -q --out " + d + ".jsonl");
    }
}

/// The rows of `path` by method, in pair order.
inline std::map<std::string, std::vector<ResultRow>> RowsByMethod(const std::string& path) {
    std::map<std::string, std::vector<ResultRow>> out;
    for (ResultRow& r : ReadResultRows(path)) out[r.method].push_back(std::move(r));
    return out;
}

/// Mean of a metric over rows.
template <class Get>
double MeanOf(const std::vector<ResultRow>& rows, Get get) {
    double sum = 0.0;
    for (const ResultRow& r : rows) sum += get(r.metrics);
    return rows.empty() ? std::nan("") : sum / static_cast<double>(rows.size());
}

}  // namespace regbench::testing
