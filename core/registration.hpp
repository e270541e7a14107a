#pragma once
// The one interface every registration method implements.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <string>

#include "core/point_cloud.hpp"

namespace regbench {

enum class AlignStatus { kOk, kFailed };

/// A method may put seconds spent not computing (e.g. waiting for a process-wide lock of a
/// library) under this key of AlignResult::extra; Align subtracts them from `seconds`.
constexpr char kExcludedSecondsKey[] = "excluded_seconds";

/// What a method returns for one pair. Methods never see ground truth.
struct AlignResult {
    Transform T_target_source = Transform::Identity();  ///< maps source into the target frame
    int iterations = 0;
    std::string stop_reason;  ///< e.g. "converged", "max_iterations", "line_search_failed"
    double seconds = 0.0;     ///< wall time of the DoAlign call (steady_clock)
    /// CPU time of the DoAlign call (see CpuStopwatch): the calling thread's CPU clock when
    /// AlignContext::threads is 1, the whole process's (getrusage) when it is more, so OpenMP
    /// workers count. Unlike `seconds` it does not grow when other processes share the core.
    double cpu_seconds = 0.0;
    std::string cpu_scope = "thread";  ///< "thread" or "process": which clock cpu_seconds read
    AlignStatus status = AlignStatus::kOk;
    std::string message;  ///< empty when ok; why it failed otherwise
    double scale = 1.0;   ///< estimated scale when a method estimates one (else 1)
    nlohmann::json extra = nlohmann::json::object();  ///< method-specific diagnostics
};

const char* ToString(AlignStatus status);

/// Per-call context every method receives: which pair of which benchmark this is, so a method
/// that draws random numbers (FPS starts, RANSAC, library-global RNGs) draws the same numbers
/// for the same pair whatever the order, sharding or --jobs of the run.
struct AlignContext {
    std::uint64_t seed = 0;        ///< benchmark seed (the pair file's generation seed)
    std::uint64_t pair_index = 0;  ///< index of the pair in its pair file
    int threads = 1;               ///< threads the method may use inside this call
    /// Optional start T_target_source for methods that refine (ICP and the like); methods that
    /// cannot use one ignore it.
    std::optional<Transform> initial_guess;

    /// 64-bit seed of this pair's method RNG stream: PairSeed mixed with a constant, so it never
    /// equals the stream that generated the pair itself.
    std::uint64_t MethodSeed() const;
    /// A fresh RNG seeded with MethodSeed() (each call returns the same stream).
    std::mt19937_64 MakeRng() const { return std::mt19937_64(MethodSeed()); }
    /// MethodSeed() folded into 31 bits, for libraries that take an int seed (Open3D, torch).
    int IntSeed() const { return static_cast<int>(MethodSeed() & 0x7fffffffULL); }
};

/// Base class. `Align` validates input, times the call and turns exceptions, NaNs and
/// non-rigid outputs into a failed status; subclasses implement `DoAlign`.
/// Thread-safety: an instance may keep scratch buffers; use one instance per thread.
class RegistrationMethod {
public:
    virtual ~RegistrationMethod() = default;
    virtual std::string Name() const = 0;
    /// Effective parameters, defaults filled in (recorded in every result row).
    virtual nlohmann::json Params() const = 0;

    /// Estimates T_target_source. Never throws.
    AlignResult Align(const PointCloud& source, const PointCloud& target,
                      const AlignContext& context = {});

protected:
    virtual AlignResult DoAlign(const PointCloud& source, const PointCloud& target,
                                const AlignContext& context) = 0;
    /// Methods that estimate a similarity transform on request return true here, so Align
    /// accepts s*R (it still requires R itself to be a rotation).
    virtual bool AllowsScale() const { return false; }
};

/// Checks one input cloud; returns an empty string when fine, else why not
/// ("source cloud is empty", "target cloud has 2 points (need >= 3)", "... non-finite ...").
std::string ValidateCloud(const PointCloud& cloud, const std::string& which);

}  // namespace regbench

#include <functional>
#include <map>
#include <memory>

namespace regbench {

/// How a method's time per iteration grows with the cloud sizes N (source) and M (target): what
/// the scale guard (runners/scale_guard.hpp) asks of each method before a run.
enum class CostClass {
    kConstant,    ///< independent of the clouds (identity)
    kNearLinear,  ///< O((N + M) log M): kd-tree, voxel or lattice based
    kQuadratic,   ///< O(N * M): dense kernel sums over all point pairs
};

/// What the registry knows about a method: each method's file provides one of these
/// (e.g. `MethodInfo CpdMethodInfo();`), and runners/registry.cpp lists them.
struct MethodInfo {
    std::string name;     ///< registry name, e.g. "cpd"
    std::string summary;  ///< one line: what it is and which implementation
    /// The row of the OGMM paper's tables this method fills (e.g. "CPD"); "" = none. The
    /// reports name the paper's rows by it (PaperTableOptions::paper_rows).
    std::string paper_label;
    /// parameter name -> one-line meaning (units, range, why this default)
    std::map<std::string, std::string> param_docs;
    /// Default parameters (what Params() returns for an empty JSON object).
    nlohmann::json defaults;
    /// The parameters' JSON Schema (core/params.hpp ParamSchemaOf),
    /// or null for methods described by hand.
    nlohmann::json schema;
    /// The method's cost class under resolved parameters `params` (its options' Cost()).
    std::function<CostClass(const nlohmann::json& params)> cost;
    /// Creates an instance; throws std::invalid_argument on unknown keys / bad values.
    std::function<std::unique_ptr<RegistrationMethod>(const nlohmann::json&)> create;
};

}  // namespace regbench
