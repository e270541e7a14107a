// The GCC vector types below (and fast_exp::Polynomial on them) never cross a function
// boundary (all always_inline), so GCC's note that passing them by value changes the ABI
// without AVX does not apply; it is silenced for this file, before the header that uses them.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
#include "gmm/gauss_sum.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/nanoflann_adaptor.hpp"

namespace regbench {

SimdLevel SimdCap() {
    static const SimdLevel cap = [] {
        const char* value = std::getenv("REGBENCH_SIMD");
        const std::string name = value == nullptr ? "" : value;
        if (name.empty() || name == "avx512") return SimdLevel::kAvx512;
        if (name == "avx2") return SimdLevel::kAvx2;
        if (name == "baseline") return SimdLevel::kBaseline;
        throw std::invalid_argument("REGBENCH_SIMD='" + name +
                                    "' is not one of avx512, avx2, baseline");
    }();
    return cap;
}

namespace {

/// Float partial sums run over at most this many terms before they are added into double.
constexpr Eigen::Index kChunk = 256;

using Tree = CloudKdTree;

using Range = std::pair<Eigen::Index, Eigen::Index>;

/// A point leaf that may hold neighbours of a query leaf: its range and the squared
/// distance from its sphere's centre within which a query point can reach it.
struct Candidate {
    Eigen::Vector3d centre;
    double reach2;  ///< (radius + cutoff)^2
    Eigen::Index begin, end;
};

/// Point leaves whose spheres come within `cutoff` of the `query` node's sphere, in stored
/// order (found by walking the point tree from the root).
void CollectCandidates(const BlockedCloud::Node& query, const BlockedCloud& points, double cutoff,
                       std::vector<int>& stack, std::vector<Candidate>& candidates) {
    candidates.clear();
    stack.assign(1, 0);
    const auto& nodes = points.nodes();
    while (!stack.empty()) {
        const BlockedCloud::Node& n = nodes[static_cast<size_t>(stack.back())];
        stack.pop_back();
        const double gap = (n.centre - query.centre).norm() - n.radius - query.radius;
        if (gap > cutoff) continue;
        if (n.child1 < 0) {
            const double reach = n.radius + cutoff;
            candidates.push_back({n.centre, reach * reach, n.begin, n.end});
        } else {
            stack.push_back(n.child2);  // child1 holds the lower range: pop it first
            stack.push_back(n.child1);
        }
    }
}

/// Everything the inner loop needs for one query leaf.
struct LeafJob {
    const float* qx;
    const float* qy;
    const float* qz;
    Eigen::Index q_begin, q_end;
    const float* px;
    const float* py;
    const float* pz;
    const float* w;
    const Candidate* candidates;
    size_t num_candidates;
    Range* ranges;  ///< scratch, num_candidates entries
    float neg_inv_two_sigma2;
    float cutoff2;
    double* m0;  ///< indexed by query stored index
    double* m1;  ///< row-major (query, 3) or nullptr
};

struct ChunkSums {
    float s0, s1, s2, s3;
};

/// Float SIMD sums over one chunk of <= kChunk points: sum w k, sum w k p (p = x, y, z).
/// Only locals and restrict pointers in the loop, so it vectorises.
template <bool kWeighted, bool kMoment>
__attribute__((always_inline)) inline ChunkSums SumChunk(
    const float* __restrict px, const float* __restrict py, const float* __restrict pz,
    const float* __restrict w, Eigen::Index count, float qx, float qy, float qz,
    float neg_inv_two_sigma2, float cutoff2) {
    // Eight independent lanes (one AVX register) written as plain arrays: GCC vectorises
    // this without -ffast-math, and the lane order fixes the summation order.
    constexpr int kLanes = 8;
    float l0[kLanes] = {}, l1[kLanes] = {}, l2[kLanes] = {}, l3[kLanes] = {};
    const auto lane_term = [&](Eigen::Index j, float& a0, float& a1, float& a2, float& a3) {
        const float dx = qx - px[j];
        const float dy = qy - py[j];
        const float dz = qz - pz[j];
        const float d2 = dx * dx + dy * dy + dz * dz;
        float k = FastExp(d2 * neg_inv_two_sigma2);
        k = d2 <= cutoff2 ? k : 0.0f;
        if (kWeighted) k *= w[j];
        a0 += k;
        if (kMoment) {
            a1 += k * px[j];
            a2 += k * py[j];
            a3 += k * pz[j];
        }
    };
    Eigen::Index j = 0;
    for (; j + kLanes <= count; j += kLanes) {
        for (int l = 0; l < kLanes; ++l) lane_term(j + l, l0[l], l1[l], l2[l], l3[l]);
    }
    for (int l = 0; j < count; ++j, ++l) lane_term(j, l0[l], l1[l], l2[l], l3[l]);
    float s0 = 0.0f, s1 = 0.0f, s2 = 0.0f, s3 = 0.0f;
    for (int l = 0; l < kLanes; ++l) {
        s0 += l0[l];
        s1 += l1[l];
        s2 += l2[l];
        s3 += l3[l];
    }
    return {s0, s1, s2, s3};
}

/// The kernel: for each query in the leaf, the candidate leaves its own position can reach
/// (merged into contiguous ranges), then float SIMD sums over chunks of each range,
/// accumulated in double. Written once, compiled for AVX2+FMA and for the baseline ISA.
/// Returns the number of kernel evaluations.
template <bool kWeighted, bool kMoment>
__attribute__((always_inline)) inline std::int64_t EvaluateLeafImpl(const LeafJob& job) {
    std::int64_t evaluated = 0;
    for (Eigen::Index i = job.q_begin; i < job.q_end; ++i) {
        const float qx = job.qx[i], qy = job.qy[i], qz = job.qz[i];
        const Eigen::Vector3d q(qx, qy, qz);
        size_t num_ranges = 0;
        for (size_t c = 0; c < job.num_candidates; ++c) {
            const Candidate& cand = job.candidates[c];
            if ((q - cand.centre).squaredNorm() > cand.reach2) continue;
            if (num_ranges > 0 && job.ranges[num_ranges - 1].second == cand.begin) {
                job.ranges[num_ranges - 1].second = cand.end;
            } else {
                job.ranges[num_ranges++] = {cand.begin, cand.end};
            }
        }
        double a0 = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
        for (size_t r = 0; r < num_ranges; ++r) {
            const Range range = job.ranges[r];
            evaluated += range.second - range.first;
            for (Eigen::Index c0 = range.first; c0 < range.second; c0 += kChunk) {
                const Eigen::Index c1 = std::min(range.second, c0 + kChunk);
                const ChunkSums s = SumChunk<kWeighted, kMoment>(
                    job.px + c0, job.py + c0, job.pz + c0, job.w ? job.w + c0 : nullptr, c1 - c0,
                    qx, qy, qz, job.neg_inv_two_sigma2, job.cutoff2);
                a0 += s.s0;
                if (kMoment) {
                    a1 += s.s1;
                    a2 += s.s2;
                    a3 += s.s3;
                }
            }
        }
        job.m0[i] = a0;
        if (kMoment) {
            job.m1[3 * i] = a1;
            job.m1[3 * i + 1] = a2;
            job.m1[3 * i + 2] = a3;
        }
    }
    return evaluated;
}

#if defined(__x86_64__) && defined(__GNUC__)
/// x86-64-v4 (AVX-512) clones: the lane order is the same, so results match the AVX2 build up
/// to FMA contraction. REGBENCH_SIMD caps the choice, so one machine can run every clone (the
/// `simd_*` tests in tests/CMakeLists.txt do).
#define REGBENCH_V4_TARGET "avx512f,avx512vl,avx512bw,avx512dq,avx2,fma"

bool HasAvx2Fma() {
    static const bool has = SimdCap() >= SimdLevel::kAvx2 && __builtin_cpu_supports("avx2") &&
                            __builtin_cpu_supports("fma");
    return has;
}
bool HasAvx512() {
    static const bool has = SimdCap() >= SimdLevel::kAvx512 && __builtin_cpu_supports("avx512f") &&
                            __builtin_cpu_supports("avx512vl") &&
                            __builtin_cpu_supports("avx512bw") &&
                            __builtin_cpu_supports("avx512dq");
    return has;
}

// One clone of `body` per instruction set. `body` must be an always_inline lambda calling
// always_inline kernels, so its whole loop is compiled with the clone's target.
template <class Body>
__attribute__((target(REGBENCH_V4_TARGET))) auto RunV4(const Body& body) {
    return body();
}
template <class Body>
__attribute__((target("avx2,fma"))) auto RunAvx2(const Body& body) {
    return body();
}
#endif

/// Runs `body` compiled for the best instruction set this CPU has (AVX-512, AVX2+FMA or the
/// baseline), chosen at run time: every SIMD kernel in this file is dispatched through here.
template <class Body>
auto RunBestIsa(const Body& body) {
#if defined(__x86_64__) && defined(__GNUC__)
    if (HasAvx512()) return RunV4(body);
    if (HasAvx2Fma()) return RunAvx2(body);
#endif
    return body();
}

template <bool kWeighted, bool kMoment>
std::int64_t EvaluateLeaf(const LeafJob& job) {
    return RunBestIsa([&]() __attribute__((always_inline)) {
        return EvaluateLeafImpl<kWeighted, kMoment>(job);
    });
}

std::int64_t Dispatch(const LeafJob& job, bool weighted, bool moment) {
    if (weighted) {
        return moment ? EvaluateLeaf<true, true>(job) : EvaluateLeaf<true, false>(job);
    }
    return moment ? EvaluateLeaf<false, true>(job) : EvaluateLeaf<false, false>(job);
}

// GCC vector types of kLanes floats: the kernel below is instantiated with the register width
// of each clone (16 lanes for AVX-512, 8 for AVX2, 4 for the SSE2 baseline; a type wider than
// the clone's registers is split badly: 16 lanes under AVX2 ran 11x the floor).
// Spelled out per width: GCC 12 silently drops a template-dependent vector_size (the "vector"
// becomes one float).
template <int kLanes>
struct Lanes;
template <>
struct Lanes<16> {
    using Floats = float __attribute__((vector_size(64)));
    using Ints = std::int32_t __attribute__((vector_size(64)));
};
template <>
struct Lanes<8> {
    using Floats = float __attribute__((vector_size(32)));
    using Ints = std::int32_t __attribute__((vector_size(32)));
};
template <>
struct Lanes<4> {
    using Floats = float __attribute__((vector_size(16)));
    using Ints = std::int32_t __attribute__((vector_size(16)));
};

/// 2^y for y <= 0 on kLanes lanes: FastExp's polynomial and 2^n scaling, with the reduction
/// done in base 2. The argument already carries log2(e) (folded into the caller's coordinate
/// scaling), so y = n + f splits with two additions (f = y - n is exact) and r = f ln 2 takes
/// one multiply where FastExp spends three FMAs; no upper clamp, since y <= 0. Exactly 0 below
/// the same underflow point as FastExp.
template <int kLanes>
__attribute__((always_inline)) inline typename Lanes<kLanes>::Floats Exp2NonPositive(
    typename Lanes<kLanes>::Floats y) {
    using Floats = typename Lanes<kLanes>::Floats;
    using Ints = typename Lanes<kLanes>::Ints;
    using fast_exp::kShifter, fast_exp::kShifterBits;
    constexpr float kLn2 = 0.693147180559945309f;
    constexpr float kMinArg = kFastExpMinArg * fast_exp::kLog2e;  // FastExp's floor, base 2
    const Floats yc = y < kMinArg ? kMinArg : y;
    const Floats t = yc + kShifter;  // its low mantissa bits hold n = round(y)
    const Floats n = t - kShifter;
    const Floats r = (yc - n) * kLn2;
    const Floats p = fast_exp::Polynomial(r);
    const Ints scale_bits = ((Ints)t - (kShifterBits - 127)) << 23;  // 2^n
    const Floats out = p * (Floats)scale_bits;
    return y < kMinArg ? Floats{} : out;
}

/// One target's kernel column over points pre-scaled by sqrt(log2(e) / (2 sigma^2)):
/// row[i] = 2^-|q - p_i|^2 = exp(-|q - p_i|^2 / (2 sigma^2)) in unscaled units, and its
/// sum (kLanes float lanes per chunk of kChunk, chunks added in double). One loop: exp, store
/// and sum with the lanes in registers; `count` is a multiple of kKernelRowPad (callers pad),
/// so no scalar or masked tail.
template <int kLanes>
__attribute__((always_inline)) inline double KernelRowImpl(
    float* __restrict row, const float* __restrict px, const float* __restrict py,
    const float* __restrict pz, Eigen::Index count, float qx, float qy, float qz) {
    static_assert(kKernelRowPad % kLanes == 0, "the padding must fill whole vectors");
    using Floats = typename Lanes<kLanes>::Floats;
    static_assert(sizeof(Floats) == kLanes * sizeof(float), "a vector of kLanes floats");
    const auto load = [](const float* p) __attribute__((always_inline)) {
        Floats v;
        std::memcpy(&v, p, sizeof v);
        return v;
    };
    double total[kLanes] = {};
    for (Eigen::Index c0 = 0; c0 < count; c0 += kChunk) {
        const Eigen::Index c1 = std::min(count, c0 + kChunk);
        Floats sum = {};
        for (Eigen::Index i = c0; i < c1; i += kLanes) {
            const Floats dx = qx - load(px + i), dy = qy - load(py + i), dz = qz - load(pz + i);
            const Floats k = Exp2NonPositive<kLanes>(-(dx * dx) - dy * dy - dz * dz);
            std::memcpy(row + i, &k, sizeof k);
            sum += k;
        }
        for (int l = 0; l < kLanes; ++l) total[l] += sum[l];
    }
    double s = 0.0;
    for (int l = 0; l < kLanes; ++l) s += total[l];
    return s;
}

/// acc{0,1,2,3}[i] += row[i] * (w, wx, wy, wz) for i in [0, count): one target's share of
/// p1 and PX, w = 1 / (den + c), from its kernel column while it is still in L1.
__attribute__((always_inline)) inline void AxpyRowImpl(const float* __restrict row,
                                                       Eigen::Index count, float w, float wx,
                                                       float wy, float wz, float* __restrict acc0,
                                                       float* __restrict acc1,
                                                       float* __restrict acc2,
                                                       float* __restrict acc3) {
    for (Eigen::Index i = 0; i < count; ++i) {
        const float k = row[i];
        acc0[i] += k * w;
        acc1[i] += k * wx;
        acc2[i] += k * wy;
        acc3[i] += k * wz;
    }
}

/// Four AxpyRowImpl calls fused: each accumulator element is loaded and stored once and gets
/// the four targets' terms in target order (the same operations, hence the same bits).
__attribute__((always_inline)) inline void AxpyRows4Impl(
    const float* __restrict rows, Eigen::Index stride, Eigen::Index count,
    const float* __restrict w, float* __restrict acc0, float* __restrict acc1,
    float* __restrict acc2, float* __restrict acc3) {
    const float* __restrict r0 = rows;
    const float* __restrict r1 = rows + stride;
    const float* __restrict r2 = rows + 2 * stride;
    const float* __restrict r3 = rows + 3 * stride;
    for (Eigen::Index i = 0; i < count; ++i) {
        float a0 = acc0[i], a1 = acc1[i], a2 = acc2[i], a3 = acc3[i];
        const float k0 = r0[i], k1 = r1[i], k2 = r2[i], k3 = r3[i];
        a0 += k0 * w[0];
        a1 += k0 * w[1];
        a2 += k0 * w[2];
        a3 += k0 * w[3];
        a0 += k1 * w[4];
        a1 += k1 * w[5];
        a2 += k1 * w[6];
        a3 += k1 * w[7];
        a0 += k2 * w[8];
        a1 += k2 * w[9];
        a2 += k2 * w[10];
        a3 += k2 * w[11];
        a0 += k3 * w[12];
        a1 += k3 * w[13];
        a2 += k3 * w[14];
        a3 += k3 * w[15];
        acc0[i] = a0;
        acc1[i] = a1;
        acc2[i] = a2;
        acc3[i] = a3;
    }
}

}  // namespace

float KernelRowScale(double sigma2) {
    return static_cast<float>(std::sqrt(M_LOG2E / (2.0 * sigma2)));
}

double KernelRow(const FloatPoints& points, const Eigen::Vector3f& q, float* row) {
    if (points.count % kKernelRowPad != 0) {
        throw std::invalid_argument("KernelRow: point count must be a multiple of " +
                                    std::to_string(kKernelRowPad) + " (pad the arrays)");
    }
    // Not RunBestIsa: each clone gets the vector width of its registers.
#if defined(__x86_64__) && defined(__GNUC__)
    if (HasAvx512()) {
        return RunV4([&]() __attribute__((always_inline)) {
            return KernelRowImpl<16>(row, points.x, points.y, points.z, points.count, q.x(), q.y(),
                                     q.z());
        });
    }
    if (HasAvx2Fma()) {
        return RunAvx2([&]() __attribute__((always_inline)) {
            return KernelRowImpl<8>(row, points.x, points.y, points.z, points.count, q.x(), q.y(),
                                    q.z());
        });
    }
#endif
    return KernelRowImpl<4>(row, points.x, points.y, points.z, points.count, q.x(), q.y(), q.z());
}

void AxpyRow(const float* row, Eigen::Index count, const std::array<float, 4>& w,
             const std::array<float*, 4>& acc) {
    RunBestIsa([&]() __attribute__((always_inline)) {
        AxpyRowImpl(row, count, w[0], w[1], w[2], w[3], acc[0], acc[1], acc[2], acc[3]);
    });
}

void AxpyRows4(const float* rows, Eigen::Index stride, Eigen::Index count,
               const std::array<std::array<float, 4>, 4>& w, const std::array<float*, 4>& acc) {
    RunBestIsa([&]() __attribute__((always_inline)) {
        AxpyRows4Impl(rows, stride, count, w[0].data(), acc[0], acc[1], acc[2], acc[3]);
    });
}

namespace {

/// Copies nanoflann's tree into BlockedCloud nodes (pre-order), returning the node index.
template <class NodePtr>
int FlattenTree(NodePtr node, std::vector<BlockedCloud::Node>& nodes, std::vector<int>& leaves,
                Eigen::Index& next_begin) {
    const int id = static_cast<int>(nodes.size());
    nodes.emplace_back();
    if (node->child1 == nullptr && node->child2 == nullptr) {
        const auto begin = static_cast<Eigen::Index>(node->node_type.lr.left);
        const auto end = static_cast<Eigen::Index>(node->node_type.lr.right);
        nodes[static_cast<size_t>(id)].begin = begin;
        nodes[static_cast<size_t>(id)].end = end;
        leaves.push_back(id);
        next_begin = end;
        return id;
    }
    const int c1 = FlattenTree(node->child1, nodes, leaves, next_begin);
    const int c2 = FlattenTree(node->child2, nodes, leaves, next_begin);
    auto& n = nodes[static_cast<size_t>(id)];
    n.child1 = c1;
    n.child2 = c2;
    n.begin = nodes[static_cast<size_t>(c1)].begin;
    n.end = nodes[static_cast<size_t>(c2)].end;
    return id;
}

}  // namespace

BlockedCloud::BlockedCloud(const PointCloud& cloud, const Eigen::Vector3d& origin)
    : origin_(origin) {
    const Eigen::Index n = cloud.rows();
    if (n == 0) throw std::invalid_argument("BlockedCloud: cloud is empty");
    bbox_diagonal_ = (cloud.colwise().maxCoeff() - cloud.colwise().minCoeff()).norm();
    const PointCloud shifted = cloud.rowwise() - origin.transpose();
    CloudAdaptor adaptor{shifted};
    Tree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(kLeafSize));
    tree.buildIndex();
    order_.assign(tree.vAcc.begin(), tree.vAcc.end());
    Eigen::Index next_begin = 0;
    FlattenTree(tree.root_node, nodes_, leaves_, next_begin);

    local_.resize(n, 3);
    for (Eigen::Index k = 0; k < n; ++k)
        local_.row(k) = shifted.row(order_[static_cast<size_t>(k)]);
    // Bounding sphere of each node: centre of its box, radius to the farthest point.
    centre0_.resize(nodes_.size());
    radius0_.resize(nodes_.size());
    for (size_t id = 0; id < nodes_.size(); ++id) {
        const auto& node = nodes_[id];
        const auto block = local_.middleRows(node.begin, node.end - node.begin);
        const Eigen::Vector3d centre =
            0.5 * (block.colwise().maxCoeff() + block.colwise().minCoeff()).transpose();
        centre0_[id] = centre;
        radius0_[id] =
            std::sqrt((block.rowwise() - centre.transpose()).rowwise().squaredNorm().maxCoeff());
    }
    x_.resize(static_cast<size_t>(n));
    y_.resize(static_cast<size_t>(n));
    z_.resize(static_cast<size_t>(n));
    SetTransform(Transform::Identity());
}

void BlockedCloud::SetTransform(const Transform& T) {
    const Eigen::Matrix3d sR = T.topLeftCorner<3, 3>();
    const double s = sR.col(0).norm();
    // T acts on absolute coordinates: T(o + p) - o = sR p + (sR o + t - o).
    const Eigen::Vector3d shift = sR * origin_ + T.topRightCorner<3, 1>() - origin_;
    for (Eigen::Index k = 0; k < local_.rows(); ++k) {
        const Eigen::Vector3d p = sR * local_.row(k).transpose() + shift;
        const auto ku = static_cast<size_t>(k);
        x_[ku] = static_cast<float>(p.x());
        y_[ku] = static_cast<float>(p.y());
        z_[ku] = static_cast<float>(p.z());
    }
    for (size_t id = 0; id < nodes_.size(); ++id) {
        nodes_[id].centre = sR * centre0_[id] + shift;
        // Float rounding of the coordinates can move a point by ~1e-7 relative; pad for it.
        nodes_[id].radius = s * radius0_[id] * (1.0 + 1e-6) + 1e-6;
    }
}

void KernelSums(const BlockedCloud& queries, const BlockedCloud& points, double sigma2,
                double cutoff_radius, const float* weights, bool want_first_moment,
                KernelSumResult& out) {
    if (!(sigma2 > 0.0) || !std::isfinite(sigma2)) {
        throw std::invalid_argument("KernelSums: sigma2 must be positive and finite");
    }
    if ((queries.origin() - points.origin()).norm() != 0.0) {
        throw std::invalid_argument("KernelSums: queries and points must share one origin");
    }
    const Eigen::Index nq = queries.size();
    out.m0.resize(nq);
    if (want_first_moment) out.m1.resize(nq, 3);
    const double cutoff = std::min(cutoff_radius, std::sqrt(2.0 * sigma2 * -kFastExpMinArg));
    const auto& leaves = queries.leaves();
    const int num_leaves = static_cast<int>(leaves.size());
    std::int64_t pairs = 0;
    const bool parallel = omp_get_max_threads() > 1 && num_leaves > 1;
#pragma omp parallel if (parallel) reduction(+ : pairs)
    {
        std::vector<int> stack;
        std::vector<Candidate> candidates;
        std::vector<Range> ranges;
        LeafJob job{queries.x(),
                    queries.y(),
                    queries.z(),
                    0,
                    0,
                    points.x(),
                    points.y(),
                    points.z(),
                    weights,
                    nullptr,
                    0,
                    nullptr,
                    static_cast<float>(-0.5 / sigma2),
                    static_cast<float>(cutoff * cutoff),
                    out.m0.data(),
                    want_first_moment ? out.m1.data() : nullptr};
#pragma omp for schedule(dynamic, 1)
        for (int l = 0; l < num_leaves; ++l) {
            const auto& leaf = queries.nodes()[static_cast<size_t>(leaves[static_cast<size_t>(l)])];
            CollectCandidates(leaf, points, cutoff, stack, candidates);
            ranges.resize(candidates.size());
            job.q_begin = leaf.begin;
            job.q_end = leaf.end;
            job.candidates = candidates.data();
            job.num_candidates = candidates.size();
            job.ranges = ranges.data();
            pairs += Dispatch(job, weights != nullptr, want_first_moment);
        }
    }
    out.evaluated_pairs = pairs;
}

namespace {
__attribute__((always_inline)) inline double FastExpPassImpl(const float* __restrict x,
                                                             float* __restrict y, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) y[i] = FastExp(x[i]);
    double s = 0.0;
    for (std::size_t i = 0; i < n; i += 4096) s += y[i];  // touch, do not re-add everything
    return s;
}
}  // namespace

double FastExpPass(const float* x, float* y, std::size_t n) {
    return RunBestIsa([&]() __attribute__((always_inline)) { return FastExpPassImpl(x, y, n); });
}

double UnderflowRadiusSigmas() { return std::sqrt(2.0 * -kFastExpMinArg); }

}  // namespace regbench
