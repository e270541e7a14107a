#include "core/registration.hpp"

#include <chrono>
#include <exception>
#include <limits>

#include "core/coordinate_limit.hpp"
#include "core/cpu_time.hpp"
#include "core/enum_names.hpp"
#include "core/rng.hpp"
#include "core/transform.hpp"

namespace regbench {

namespace {
constexpr EnumName<AlignStatus> kAlignStatusNames[] = {
    {AlignStatus::kOk, "ok"},
    {AlignStatus::kFailed, "failed"},
};
}  // namespace

const char* ToString(AlignStatus status) { return EnumToString(kAlignStatusNames, status); }

std::string ValidateCloud(const PointCloud& cloud, const std::string& which) {
    constexpr Eigen::Index kMinPoints = 3;
    if (cloud.rows() == 0) return which + " cloud is empty";
    if (cloud.rows() < kMinPoints) {
        return which + " cloud has " + std::to_string(cloud.rows()) + " points (need >= 3)";
    }
    if (!cloud.allFinite()) return which + " cloud has non-finite (NaN or Inf) coordinates";
    // PCL (GICP, NDT) and the float E-steps square coordinates in float: beyond kMaxCoordinate
    // (point_cloud.hpp) PCL can abort the whole process, so it fails here as a row.
    if (cloud.cwiseAbs().maxCoeff() > kMaxCoordinate) {
        return which + " cloud has coordinates beyond the limit |x| <= 1e15";
    }
    return {};
}

std::uint64_t AlignContext::MethodSeed() const {
    constexpr std::uint64_t kMethodStream = 0x4D4554484F44ULL;  // "METHOD": not the pair stream
    return SplitMix64(PairSeed(seed, pair_index) ^ kMethodStream);
}

namespace {
AlignResult Failed(std::string message, double seconds = 0.0, double cpu_seconds = 0.0) {
    AlignResult r;
    r.cpu_seconds = cpu_seconds;
    r.status = AlignStatus::kFailed;
    r.message = std::move(message);
    r.stop_reason = "error";
    r.seconds = seconds;
    return r;
}
}  // namespace

AlignResult RegistrationMethod::Align(const PointCloud& source, const PointCloud& target,
                                      const AlignContext& context) {
    for (const auto& problem : {ValidateCloud(source, "source"), ValidateCloud(target, "target")}) {
        if (!problem.empty()) return Failed(Name() + ": " + problem);
    }
    const auto start = std::chrono::steady_clock::now();
    const CpuStopwatch cpu(context.threads);
    AlignResult result;
    try {
        result = DoAlign(source, target, context);
    } catch (const std::exception& e) {
        result = Failed(Name() + ": " + e.what());
    } catch (...) {
        result = Failed(Name() + ": unknown exception");
    }
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // Read right after the call: the checks below are not the method's time.
    result.cpu_seconds = cpu.Elapsed();
    result.cpu_scope = cpu.Scope();
    if (result.extra.is_object() && result.extra.contains(kExcludedSecondsKey)) {
        result.seconds -= result.extra[kExcludedSecondsKey].get<double>();
    }
    if (result.status != AlignStatus::kOk) {
        result.T_target_source = Transform::Identity();
        return result;
    }
    Eigen::Matrix3d sR = result.T_target_source.topLeftCorner<3, 3>();
    if (!result.T_target_source.allFinite()) {
        return Failed(Name() + ": produced a non-finite transform", result.seconds,
                      result.cpu_seconds);
    }
    if (result.T_target_source.topRightCorner<3, 1>().cwiseAbs().maxCoeff() > kMaxTranslation) {
        return Failed(Name() + ": produced a translation beyond the coordinate limit (2e15)",
                      result.seconds, result.cpu_seconds);
    }
    constexpr double kRotationTol = 1e-6;
    // A last row other than (0, 0, 0, 1) (a Python method's [0.5, 0, 0, 1]) is no rigid
    // transform either, whatever its top rows hold.
    const Eigen::RowVector4d bottom = result.T_target_source.row(3);
    if ((bottom - Eigen::RowVector4d(0.0, 0.0, 0.0, 1.0)).cwiseAbs().maxCoeff() > kRotationTol) {
        return Failed(Name() + ": produced a transform whose last row is not (0, 0, 0, 1)",
                      result.seconds, result.cpu_seconds);
    }
    const double s = AllowsScale() ? std::cbrt(sR.determinant()) : 1.0;
    if (!(s > 0.0) || !IsRotation(sR / s, kRotationTol)) {
        return Failed(Name() + ": produced a non-rigid transform", result.seconds,
                      result.cpu_seconds);
    }
    if (!AllowsScale()) result.scale = 1.0;
    return result;
}

}  // namespace regbench
