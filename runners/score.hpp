#pragma once
// `regbench score`: result rows for transforms computed anywhere (another library, Python),
// scored on a frozen pair file exactly as `run` scores its own methods.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/metrics.hpp"
#include "core/point_cloud.hpp"
#include "core/transform.hpp"

namespace regbench {

/// Default tolerance of the rigidity check: max |R^T R - I|, |det R - 1| and the bottom row's
/// distance from (0, 0, 0, 1). Loose enough for float32 output, tight enough to catch a
/// scaled, sheared or transposed-by-mistake matrix.
constexpr double kDefaultRigidTolerance = 1e-4;
/// The largest --rigid-tol: 0.1 already accepts a rotation matrix 10% off; more accepted
/// scalings and shears (diag(5, 0.1, 3) with --rigid-tol 1e18) as rigid.
constexpr double kMaxRigidTolerance = 0.1;

struct ScoreOptions {
    std::string pairs_path;       ///< frozen HDF5 pair file the transforms were computed on
    std::string transforms_path;  ///< .jsonl, .csv, .log or .npy (by extension; ReadTransforms)
    std::string method;           ///< name written in every row
    nlohmann::json params = nlohmann::json::object();  ///< recorded in every row
    std::string out_path;                              ///< result JSONL (written atomically)
    EulerConvention euler = EulerConvention::kZyx;     ///< Euler angles of mae_r / rmse_r
    double rigid_tolerance = kDefaultRigidTolerance;
    /// Accept similarities s R (uniform scale s > 0, e.g. CPD with scale): checked as R after
    /// dividing s = cbrt(det) out; the row's `scale` is s and the rotation metrics use R.
    bool allow_scale = false;
    int threads = 1;  ///< recorded in rows (threads the external method used)
    /// Score transforms that record no content hash of their pair file (nothing can tell
    /// whether they were computed on this one); refused by default.
    bool allow_unhashed = false;
    MetricOptions metric_options;  ///< CCD clip, Open3D fitness / inlier RMSE threshold
    /// `--ccd-clip` was given (else the default clip is scaled by the pair file's `scale`).
    bool ccd_clip_given = false;
};

/// One transform of a transforms file.
struct ExternalTransform {
    std::size_t pair = 0;
    Transform T = Transform::Identity();  ///< maps the pair's source into its target frame
    double seconds = 0.0;                 ///< 0 when the file gives none
    double scale = 1.0;                   ///< cbrt(det) of the 3x3 block when scale is allowed
    std::string origin;                   ///< "file:line"
    /// Content hash of the pair file the transform was computed on, when the file records it
    /// (JSONL: "content_hash" or data.content_hash; either format: a "# content_hash: H"
    /// comment line, which applies to the lines after it); empty when not recorded.
    std::string content_hash;
};

/// The formats of a transforms file, chosen by its extension.
enum class TransformsFormat { kJsonl, kCsv, kLog, kNpy, kUnknown };
/// .jsonl and .json: kJsonl; .csv: kCsv; .log: kLog; .npy: kNpy; anything else kUnknown.
TransformsFormat TransformsFormatOf(const std::string& path);
/// What a transforms file's name must end in (the refusal of any other).
inline constexpr const char* kTransformsExtensions =
    "a transforms file must end in .jsonl (or .json), .csv, .log (3DMatch) or .npy (NumPy)";

/// Reads a transforms file and validates it: JSONL rows {"pair": k, "transform": 4x4,
/// "seconds": s} (a row with a "method" key other than `method` is skipped, so a `run` result
/// file can be rescored; a file whose rows name methods but never `method` is refused naming
/// the methods it holds), CSV `pair,t00,...,t23[,seconds]` (first three rows of the 4x4,
/// row-major) or `pair,t00,...,t33[,seconds]` (all four rows; an optional header line starting
/// with "pair"), a 3DMatch .log (per pair a line "i j n", then the 4 rows of the 4x4,
/// whitespace-separated; the k-th record is pair k) or a NumPy .npy of shape (num_pairs, 4, 4),
/// little-endian float64 or float32, C order (element k is pair k). '#' lines are comments in
/// the text formats ("# content_hash: H" applies to the lines after it). Throws
/// std::runtime_error naming file:line (file[k] for a .npy) for a malformed line or header, a
/// pair index outside [0, num_pairs), a pair given twice, a .log or .npy without exactly one
/// transform per pair, or a matrix that is not rigid (a similarity with `allow_scale`) within
/// `rigid_tolerance`.
std::vector<ExternalTransform> ReadTransforms(const std::string& path, std::size_t num_pairs,
                                              const std::string& method, double rigid_tolerance,
                                              bool allow_scale = false);

struct ScoreSummary {
    std::size_t rows = 0;     ///< rows written (one per pair)
    std::size_t missing = 0;  ///< pairs without a transform (status "missing")
};

/// Scores every pair of the pair file: a row per pair, `missing` for pairs the file lacks
/// (identity transform, counted as failed by `report`). Nothing is written on bad input:
/// a transform recording another pair file's content hash, or (unless `allow_unhashed`) one
/// recording none, is refused naming file:line.
ScoreSummary ScoreTransforms(const ScoreOptions& options);

}  // namespace regbench
