#pragma once
// Gaussian kernel sums for the GMM-family methods (CPD, GMMReg, FilterReg's exact mode).
// CPD's fused E-step built on them lives with CPD (baselines/cpd.hpp).
//
// The workhorse is KernelSums(queries, points): for every query q_i,
//   m0_i = sum_j w_j exp(-|q_i - p_j|^2 / 2 sigma^2),   m1_i = sum_j w_j k_ij p_j,
// evaluated in float SoA with an inline polynomial exp (FastExp) and accumulated in double,
// without ever storing the M x N kernel matrix.
//
// Pruning: both clouds are stored in nanoflann kd-tree leaf order with a bounding sphere per
// tree node. For each query leaf, the point tree is walked and only leaves whose sphere comes
// within `cutoff_radius` of the query leaf's sphere are evaluated; inside them every pair is
// still tested against the cutoff, so the result does not depend on the tree layout.
//  - Dense (exact) evaluation uses the float underflow radius sqrt(2 * 87) sigma ~ 13.2 sigma:
//    every pair it drops has k < 1.7e-38, which FastExp returns as 0 anyway, so pruning
//    never changes the dense result; it only saves time once sigma is small.
//  - Truncated evaluation uses r = truncation_sigmas * sigma (4 sigma by default, a relative
//    kernel value of exp(-8) = 3.4e-4 at the edge).
//
// Threading: OpenMP over query leaves with omp_get_max_threads() threads (one thread: no
// parallel region). Every output element is owned by one query and summed in a fixed order,
// so results are bitwise identical for any thread count.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/enum_names.hpp"
#include "core/point_cloud.hpp"

namespace regbench {

/// FastExp returns exactly 0 below this argument (exp(-87) = 1.6e-38, next to FLT_MIN).
constexpr float kFastExpMinArg = -87.0f;
/// Arguments above this are clamped (exp(88) = 1.65e38, just below FLT_MAX).
constexpr float kFastExpMaxArg = 88.0f;

/// The pieces of FastExp that CPD's base-2 kernel (KernelRow) shares, written once.
namespace fast_exp {
inline constexpr float kLog2e = 1.44269504088896341f;
inline constexpr float kShifter = 12582912.0f;  // 1.5 * 2^23: adding it rounds to an integer
inline constexpr std::int32_t kShifterBits = 0x4B400000;
/// Cephes' degree-6 polynomial for exp(r), |r| <= ln2 / 2; T is float or a GCC float vector.
template <class T>
__attribute__((always_inline)) inline T Polynomial(T r) {
    T p = r * 1.9875691500e-4f + 1.3981999507e-3f;
    p = p * r + 8.3334519073e-3f;
    p = p * r + 4.1665795894e-2f;
    p = p * r + 1.6666665459e-1f;
    p = p * r + 5.0000001201e-1f;
    return p * (r * r) + r + 1.0f;
}
}  // namespace fast_exp

/// exp(x) in float: Cody-Waite range reduction x = n ln2 + r (|r| <= ln2 / 2) and Cephes'
/// degree-6 polynomial for exp(r), then 2^n by exponent-bit arithmetic. Branch-free, so loops
/// over it vectorise without -ffast-math. Relative error below 3e-7 (~2.5 float ulp) over
/// [-87, 0], checked on 2e6 points in tests/gmm/gauss_sum_test.cpp; 0 for x < -87, exp(88) for x
/// > 88. GCC vectorises loops over it only with -fno-trapping-math in the calling file (as
/// gauss_sum.cpp is built); prefer KernelSums, which already is.
inline float FastExp(float x) {
    using fast_exp::kLog2e, fast_exp::kShifter, fast_exp::kShifterBits;
    constexpr float kLn2Hi = 0.693359375f;  // ln 2 = kLn2Hi + kLn2Lo (Cody-Waite)
    constexpr float kLn2Lo = -2.12194440e-4f;
    // min/max and a final select, not branches: loops over FastExp stay free of control flow
    // and vectorise without -ffast-math.
    const float xc = std::min(std::max(x, kFastExpMinArg), kFastExpMaxArg);
    const float t = xc * kLog2e + kShifter;  // its low mantissa bits hold n = round(x / ln 2)
    const float n = t - kShifter;
    const float r = (xc - n * kLn2Hi) - n * kLn2Lo;
    const float p = fast_exp::Polynomial(r);
    std::int32_t t_bits;
    std::memcpy(&t_bits, &t, sizeof t_bits);
    const std::int32_t scale_bits = (t_bits - kShifterBits + 127) << 23;  // 2^n
    float scale;
    std::memcpy(&scale, &scale_bits, sizeof scale);
    const float y = p * scale;
    return x < kFastExpMinArg ? 0.0f : y;
}

/// A cloud prepared for kernel sums: points in nanoflann kd-tree leaf order, float SoA
/// coordinates relative to `origin` (keeps float precision for clouds far from 0), and a
/// bounding sphere per tree node. The tree is built once in the cloud's own frame;
/// SetTransform moves the stored points by a similarity transform (s R | t) without
/// rebuilding it (spheres move rigidly, radii scale by s).
class BlockedCloud {
public:
    /// Points per kd-tree leaf: the unit of pruning and of parallel work.
    static constexpr int kLeafSize = 32;

    BlockedCloud(const PointCloud& cloud, const Eigen::Vector3d& origin);

    /// Stored coordinates become T * cloud (T = [sR t; 0 1], s > 0), still relative to origin.
    void SetTransform(const Transform& T);

    Eigen::Index size() const { return static_cast<Eigen::Index>(order_.size()); }
    /// order()[k] is the index in the input cloud of the k-th stored point.
    const std::vector<Eigen::Index>& order() const { return order_; }
    const Eigen::Vector3d& origin() const { return origin_; }
    /// Diagonal of the input cloud's axis-aligned bounding box (untransformed).
    double bbox_diagonal() const { return bbox_diagonal_; }

    struct Node {
        Eigen::Index begin = 0, end = 0;                   ///< stored-order range [begin, end)
        int child1 = -1, child2 = -1;                      ///< -1 for leaves
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< current frame, relative to origin
        double radius = 0.0;
    };
    const std::vector<Node>& nodes() const { return nodes_; }
    /// Indices into nodes() of the leaves, in stored order.
    const std::vector<int>& leaves() const { return leaves_; }
    const float* x() const { return x_.data(); }
    const float* y() const { return y_.data(); }
    const float* z() const { return z_.data(); }

private:
    Eigen::Vector3d origin_;
    double bbox_diagonal_ = 0.0;
    std::vector<Eigen::Index> order_;
    PointCloud local_;  ///< input points in stored order, relative to origin, double
    std::vector<Node> nodes_;
    std::vector<Eigen::Vector3d> centre0_;  ///< node centres before SetTransform
    std::vector<double> radius0_;
    std::vector<int> leaves_;
    std::vector<float> x_, y_, z_;
};

/// Output of KernelSums, in the *query's stored order* (see BlockedCloud::order()).
struct KernelSumResult {
    Eigen::VectorXd m0;  ///< sum_j w_j k_ij
    PointCloud m1;       ///< sum_j w_j k_ij p_j (relative to the points' origin); empty if unused
    std::int64_t evaluated_pairs = 0;  ///< kernel evaluations actually done (pruning diagnostic)
};

/// m0 (and m1 when want_first_moment) for every query; see the file comment. `weights` is in
/// the points' stored order (nullptr = all ones). Pairs farther apart than cutoff_radius
/// contribute 0. Both clouds must share the same origin. sigma2 > 0.
void KernelSums(const BlockedCloud& queries, const BlockedCloud& points, double sigma2,
                double cutoff_radius, const float* weights, bool want_first_moment,
                KernelSumResult& out);

/// The machine's exp floor: y[i] = FastExp(x[i]) for i < n, dispatched to the same ISA clones
/// as the kernel sums (bench/baselines/cpd_floor_bench.cpp times it against a CPD iteration).
/// Returns the sum of y so the work cannot be optimised away.
double FastExpPass(const float* x, float* y, std::size_t n);

/// `count` points as three float coordinate arrays (structure of arrays, as BlockedCloud keeps
/// them), the layout the SIMD kernels read.
struct FloatPoints {
    const float* x;
    const float* y;
    const float* z;
    Eigen::Index count;
};

/// Instruction sets the kernel sums below are compiled for, picked at run time.
enum class SimdLevel { kBaseline, kAvx2, kAvx512 };

/// The highest SimdLevel the kernels may use: REGBENCH_SIMD=avx2|baseline lowers it (so one
/// machine can test every clone, or time like with like across machines); unset or avx512
/// leaves the choice to the CPU. Read once; an unknown value throws std::invalid_argument.
SimdLevel SimdCap();

/// Point arrays for KernelRow are padded to a multiple of this many entries.
constexpr Eigen::Index kKernelRowPad = 16;

/// A coordinate for KernelRow's padding entries: far enough from any scaled point that its
/// kernel is exactly 0, small enough that its squared distance stays finite in float.
constexpr float kKernelRowFar = 1e18f;

/// The factor KernelRow's points and query are scaled by for bandwidth sigma^2:
/// sqrt(log2(e) / (2 sigma^2)).
float KernelRowScale(double sigma2);

/// One kernel column for CPD's fused E-step: row[i] = 2^-|q - p_i|^2 for all `points`,
/// returning sum_i row[i] (float lanes, chunks in double). Points and q come scaled by
/// KernelRowScale(sigma^2), which makes row[i] = exp(-|q - p_i|^2 / (2 sigma^2)) in the
/// unscaled coordinates with neither the bandwidth nor log2(e) costing a multiply per pair.
/// points.count must be a multiple of kKernelRowPad (pad with kKernelRowFar: the padding's
/// entries come out exactly 0); row holds points.count floats.
double KernelRow(const FloatPoints& points, const Eigen::Vector3f& q, float* row);

/// acc[c][i] += w[c] row[i] for c = 0..3 and i < count: one target's share of CPD's p1 and PX
/// with w = (1, x, y, z) / (den + c).
void AxpyRow(const float* row, Eigen::Index count, const std::array<float, 4>& w,
             const std::array<float*, 4>& acc);

/// Four targets at once: acc[c][i] += w[t][c] rows[t * stride + i] for t = 0..3 in that
/// order, so the result is bit-identical to four AxpyRow calls, with a quarter of their
/// accumulator loads and stores (the E-step's main cost beside the exponentials).
void AxpyRows4(const float* rows, Eigen::Index stride, Eigen::Index count,
               const std::array<std::array<float, 4>, 4>& w, const std::array<float*, 4>& acc);

/// Radius (in sigmas) beyond which FastExp(-d^2 / 2 sigma^2) is exactly 0: sqrt(2 * 87).
double UnderflowRadiusSigmas();

/// How to evaluate the Gaussian sums.
enum class GaussSumMode {
    kAuto,       ///< dense until the truncation rule below holds, then truncated
    kDense,      ///< exact up to float underflow
    kTruncated,  ///< always truncate at truncation_sigmas * sigma
};
REGBENCH_CHOICES(GaussSumMode, {{GaussSumMode::kAuto, "auto"},
                                {GaussSumMode::kDense, "dense"},
                                {GaussSumMode::kTruncated, "truncated"}})

/// Switch rule for GaussSumMode::kAuto (docs/probabilistic-baselines.md, CPD cost): truncate
/// when max(M, N) >= truncation_min_points and r = truncation_sigmas * sigma is below
/// truncation_max_diag_fraction of the target's bounding-box diagonal. sigma^2 starts wide
/// (sqsum), so early iterations stay dense and only the cheap late ones are truncated.
struct GaussSumOptions {
    GaussSumMode mode = GaussSumMode::kAuto;
    double truncation_sigmas = 4.0;              ///< r = k sigma; exp(-k^2/2) at the edge
    Eigen::Index truncation_min_points = 20000;  ///< auto: below this, always dense
    double truncation_max_diag_fraction = 0.25;  ///< auto: truncate once r < this * diagonal
    /// auto: cell edge, in sigmas, of the cell-compressed E-step (gmm/cell_compress.hpp);
    /// 0 disables compression. 0.25 keeps each merged term within a few percent.
    double cluster_cell_sigmas = 0.25;
    Eigen::Index cluster_min_points = 20000;  ///< auto: compress only if max(M, N) >= this
    /// auto: compress a cloud only while it has fewer than this fraction as many cells as
    /// points (late iterations, with sigma near the point spacing, stay exact).
    double cluster_max_fraction = 0.5;
};

}  // namespace regbench
