// `regbench align SRC TGT`: register two point files with any registered method, as one would
// with Open3D's or probreg's example scripts.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

#include "app/cli_numbers.hpp"
#include "app/cli_params.hpp"
#include "app/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/metrics.hpp"
#include "core/output_rule.hpp"
#include "core/transform.hpp"
#include "datasets/point_file.hpp"
#include "protocols/xyz_io.hpp"
#include "runners/align_clouds.hpp"
#include "runners/registry.hpp"
#include "runners/scale_guard.hpp"

namespace regbench::app {
namespace {

std::string FormatTransform(const Transform& T) {
    std::string out;
    for (int r = 0; r < 4; ++r) {
        out += fmt::format("{:.17g} {:.17g} {:.17g} {:.17g}\n", T(r, 0), T(r, 1), T(r, 2), T(r, 3));
    }
    return out;
}

/// No rigid transform is defined by fewer than 3 points or by points that all coincide: such a
/// cloud is refused naming its file (a method used to fail on it, or return the identity as ok).
void RefuseDegenerateCloud(const std::string& path, const PointCloud& cloud) {
    if (cloud.rows() < 3) {
        throw std::runtime_error(path + ": " + std::to_string(cloud.rows()) +
                                 " point(s); align needs at least 3");
    }
    if ((cloud.colwise().maxCoeff() - cloud.colwise().minCoeff()).maxCoeff() == 0.0) {
        throw std::runtime_error(path + ": all " + std::to_string(cloud.rows()) +
                                 " points are identical; no transform is defined by them");
    }
}

void SetupAlignCommand(CLI::App* cmd) {
    auto src = std::make_shared<std::string>();
    auto tgt = std::make_shared<std::string>();
    auto method = std::make_shared<std::string>();
    auto params = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto save_aligned = std::make_shared<std::string>();
    auto gt = std::make_shared<std::string>();
    auto normalize = std::make_shared<bool>(false);
    auto euler = std::make_shared<std::string>("zyx");
    auto seed = std::make_shared<std::uint64_t>(0);
    auto threads = std::make_shared<int>(1);
    auto nan_points = std::make_shared<std::string>("drop");
    auto force = std::make_shared<bool>(false);
    auto max_points = std::make_shared<std::size_t>(kDefaultMaxPoints);
    cmd->add_option("source", *src, "Source point file (.ply .pcd .xyz .txt .off)")->required();
    cmd->add_option("target", *tgt, "Target point file")->required();
    cmd->add_option("--method", *method, "Method name (see `regbench methods`)")->required();
    cmd->add_option("--params", *params, "JSON object of the method's parameters");
    cmd->add_option("--out", *out, "Write the 4x4 (4 lines of 4 numbers) to this file");
    cmd->add_option("--save-aligned", *save_aligned,
                    "Write the moved source (orange) and the target (blue) to this PLY file, to "
                    "open in any viewer (MeshLab, CloudCompare, Open3D)");
    cmd->add_flag("--force", *force, "Replace an existing --out");
    cmd->add_option("--gt", *gt, "Ground-truth 4x4 (same format): also print the metrics");
    cmd->add_flag("--normalize", *normalize,
                  "Move both clouds by the target's centroid and scale them by one factor into "
                  "the unit sphere before aligning, and map the result back. The clouds are "
                  "otherwise used as given; methods whose defaults assume unit-sphere objects "
                  "(fgr's voxel size, ndt's resolution, icp's correspondence distance) need "
                  "this or matching --params for clouds in other units");
    cmd->add_option("--euler", *euler, "Euler angles of mae_r with --gt: zyx (paper) | xyz")
        ->check(CLI::IsMember({"zyx", "xyz"}))
        ->capture_default_str();
    cmd->add_option("--seed", *seed, "Seed of the method's random stream")
        ->check(WholeNumber())
        ->capture_default_str();
    cmd->add_option("--threads", *threads, "Threads inside the method")
        ->check(ThreadCount())
        ->capture_default_str();
    cmd->add_option("--nan-points", *nan_points,
                    "Points of a PLY/PCD with a NaN or Inf coordinate: drop (with a warning "
                    "giving their count) | refuse (the file, naming it and the count)")
        ->check(CLI::IsMember({"drop", "refuse"}))
        ->capture_default_str();
    cmd->add_option("--max-points", *max_points,
                    "Scale guard, as run's: an O(N*M) method (a network its family declares "
                    "quadratic; cpd, gmmreg, svr in their dense modes) on a cloud above this "
                    "many points is refused before it runs; 0 = no guard")
        ->check(WholeNumber())
        ->capture_default_str();
    cmd->callback([=] {
        // One writer per output file, the one output rule (docs/usage.md, "Outputs") before
        // work; the other output counts as an input of each.
        std::vector<std::string> inputs{*src, *tgt};
        if (!gt->empty()) inputs.push_back(*gt);
        std::optional<ClaimedOutput> claim, ply_claim;
        if (!out->empty()) {
            std::vector<std::string> taken = inputs;
            if (!save_aligned->empty()) taken.push_back(*save_aligned);
            claim.emplace(*out, taken, OutputRule{*force});
        }
        if (!save_aligned->empty()) {
            std::vector<std::string> taken = inputs;
            if (!out->empty()) taken.push_back(*out);
            ply_claim.emplace(*save_aligned, taken, OutputRule{*force});
        }
        const nlohmann::json p = ParseParamsOption(*params);
        // validates name and params (a usage error)
        const auto reg = AsUsageError([&] { return CreateMethod(*method, p); });
        const NonFinitePoints non_finite =
            *nan_points == "refuse" ? NonFinitePoints::kRefuse : NonFinitePoints::kDrop;
        const PointCloud source = ReadCloudFile(*src, non_finite);
        const PointCloud target = ReadCloudFile(*tgt, non_finite);
        RefuseDegenerateCloud(*src, source);  // before any method runs; nothing is written
        RefuseDegenerateCloud(*tgt, target);
        // run()'s scale guard, one predicate with run and Python's align: rienet on 200,000
        // points asked for 160 GB and ended in a LibTorch backtrace.
        try {
            RequireCallScale(MethodSpec{*method, reg->Params()},
                             static_cast<std::size_t>(source.rows()),
                             static_cast<std::size_t>(target.rows()), *max_points);
        } catch (const std::invalid_argument& e) {
            throw std::runtime_error(std::string("align: ") + e.what() +
                                     "; pass --max-points 0 to run it as is (or a larger "
                                     "--max-points), or downsample the clouds first");
        }
        const Transform T_gt = gt->empty() ? Transform::Identity() : ReadTransformTxt(*gt);
        AlignContext context;
        context.seed = *seed;
        context.threads = *threads;
        const AlignResult r = AlignClouds(*reg, source, target, *normalize, context);
        const Transform& T = r.T_target_source;
        std::cout << FormatTransform(T);
        std::cout << fmt::format("method {} | status {} | {:.4f} s | {} iterations | {}\n",
                                 reg->Name(), ToString(r.status), r.seconds, r.iterations,
                                 r.stop_reason);
        if (!r.message.empty()) std::cout << "message: " << r.message << "\n";
        if (!gt->empty()) {
            const PairMetrics m =
                ComputeMetrics(T_gt, T, source, target, ParseEulerConvention(*euler));
            std::cout << fmt::format(
                "mae_r {:.4f} deg (euler {}) | mae_t {:.4g} | rre {:.4f} deg | rte {:.4g} | "
                "ccd {:.4g} | chamfer {:.4g}\n",
                m.mae_r, ToString(m.euler), m.mae_t, m.rre, m.rte, m.ccd, m.chamfer);
        }
        if (!out->empty()) {
            WriteFileAtomic(*out, FormatTransform(T), inputs);  // checked; never an input
        }
        if (!save_aligned->empty()) {
            WriteFileAtomic(*save_aligned, TwoCloudPlyText(Apply(T, source), target), inputs);
            std::cerr << "[align] wrote the moved source (orange) and the target (blue) to "
                      << *save_aligned << "\n";
        }
        if (r.status != AlignStatus::kOk) throw std::runtime_error(*method + " failed");
    });
}

[[maybe_unused]] const bool kAlignRegistered = RegisterCommand(
    {"align",
     "Register two point files (PLY, PCD, XYZ, OFF vertices): prints the 4x4 mapping SRC "
     "into TGT's frame, the time and the status",
     SetupAlignCommand});
}  // namespace

}  // namespace regbench::app
