#include "gmm/permutohedral.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace regbench {
namespace {

constexpr int kD = PermutohedralLattice::kDim;
constexpr int kV = PermutohedralLattice::kVertices;
constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  // packed keys never set the top bit
constexpr int kKeyBits = 21;
constexpr std::uint64_t kFibonacci = 0x9E3779B97F4A7C15ULL;  // multiplicative hashing

// Round to nearest, ties to even, in float: what the reference's SSE path
// (_mm_cvtps_epi32 under the default MXCSR rounding) does. Valid for |v| < 2^22; Embed
// rejects anything beyond the key range first.
inline float RoundNearestEven(float v) {
    constexpr float kMagic = 12582912.0f;  // 1.5 * 2^23
    return (v >= 0.0f) ? (v + kMagic) - kMagic : (v - kMagic) + kMagic;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// LatticeHashTable

LatticeHashTable::LatticeHashTable(std::size_t expected_vertices) {
    std::size_t capacity = 16;
    while (capacity < 2 * expected_vertices) capacity *= 2;
    slots_key_.assign(capacity, kEmpty);
    slots_id_.assign(capacity, -1);
    SetCapacity(capacity);
}

void LatticeHashTable::SetCapacity(std::size_t capacity) {
    mask_ = capacity - 1;
    shift_ = 64;
    for (std::size_t c = capacity; c > 1; c >>= 1) --shift_;
}

std::uint64_t LatticeHashTable::Pack(const int key[3]) {
    std::uint64_t packed = 0;
    for (int i = 0; i < 3; ++i) {
        if (key[i] > kMaxCoordinate || key[i] < -kMaxCoordinate) {
            throw std::runtime_error("permutohedral lattice: vertex coordinate " +
                                     std::to_string(key[i]) +
                                     " out of range (features too large for the kernel width)");
        }
        packed = (packed << kKeyBits) | static_cast<std::uint64_t>(key[i] + (1 << 20));
    }
    return packed;
}

std::size_t LatticeHashTable::Slot(std::uint64_t packed) const {
    // Multiply-shift hashing (Knuth): the top bits of the product mix all three fields.
    return static_cast<std::size_t>((packed * kFibonacci) >> shift_);
}

void LatticeHashTable::Grow() {
    const std::size_t capacity = 2 * slots_key_.size();
    slots_key_.assign(capacity, kEmpty);
    slots_id_.assign(capacity, -1);
    SetCapacity(capacity);
    for (std::size_t id = 0; id < keys_by_id_.size(); ++id) {
        std::size_t h = Slot(keys_by_id_[id]);
        while (slots_key_[h] != kEmpty) h = (h + 1) & mask_;
        slots_key_[h] = keys_by_id_[id];
        slots_id_[h] = static_cast<int>(id);
    }
}

int LatticeHashTable::FindOrInsert(const int key[3]) {
    if (2 * (keys_by_id_.size() + 1) > slots_key_.size()) Grow();
    const std::uint64_t packed = Pack(key);
    std::size_t h = Slot(packed);
    while (slots_key_[h] != kEmpty) {
        if (slots_key_[h] == packed) return slots_id_[h];
        h = (h + 1) & mask_;
    }
    const int id = static_cast<int>(keys_by_id_.size());
    slots_key_[h] = packed;
    slots_id_[h] = id;
    keys_by_id_.push_back(packed);
    coords_by_id_.insert(coords_by_id_.end(), key, key + 3);
    return id;
}

int LatticeHashTable::Find(const int key[3]) const {
    for (int i = 0; i < 3; ++i) {
        if (key[i] > kMaxCoordinate || key[i] < -kMaxCoordinate) return -1;
    }
    const std::uint64_t packed = Pack(key);
    std::size_t h = Slot(packed);
    while (slots_key_[h] != kEmpty) {
        if (slots_key_[h] == packed) return slots_id_[h];
        h = (h + 1) & mask_;
    }
    return -1;
}

// ---------------------------------------------------------------------------------------------
// PermutohedralLattice

PermutohedralLattice::Elevation PermutohedralLattice::ElevationFor(bool blur) {
    // Computed as the reference does: the inverse std in double rounded to float, each
    // factor in double rounded to float.
    const float inv_std_dev = static_cast<float>(
        (blur ? std::sqrt(2.0 / 3.0) : std::sqrt(1.0 / 6.0)) * static_cast<double>(kD + 1));
    Elevation e;
    for (int i = 0; i < kD; ++i) {
        e.scale[i] = static_cast<float>(1.0 / std::sqrt(static_cast<double>((i + 2) * (i + 1))) *
                                        static_cast<double>(inv_std_dev));
    }
    return e;
}

float PermutohedralLattice::SliceNormalisation() {
    return 1.0f / (1.0f + std::pow(2.0f, -static_cast<float>(kD)));
}

void PermutohedralLattice::Embed(const float feature[kDim], const Elevation& elevation,
                                 SimplexEmbedding& out) {
    constexpr float kDown = 1.0f / (kD + 1);
    constexpr float kUp = static_cast<float>(kD + 1);
    // Elevate onto the plane x . 1 = 0 of R^(d+1): y = E f (Adams et al. 2010 p. 5).
    float elevated[kV];
    float sm = 0.0f;
    for (int j = kD; j > 0; --j) {
        const float cf = feature[j - 1] * elevation.scale[j - 1];
        elevated[j] = sm - static_cast<float>(j) * cf;
        sm += cf;
    }
    elevated[0] = sm;

    // Closest remainder-0 lattice point by rounding each coordinate to a multiple of d+1.
    float rem0[kV];
    float sum = 0.0f;
    for (int i = 0; i <= kD; ++i) {
        const float v = kDown * elevated[i];
        if (!(std::fabs(v) < static_cast<float>(LatticeHashTable::kMaxCoordinate))) {
            throw std::runtime_error(
                "permutohedral lattice: feature out of range (non-finite or too large for the "
                "kernel width)");
        }
        const float r = RoundNearestEven(v);
        rem0[i] = r * kUp;
        sum += r;
    }

    // Rank of each coordinate of the remainder in decreasing order: the simplex we are in.
    // Branch-free: the comparisons are data-dependent coin flips.
    float diff[kV];
    for (int i = 0; i <= kD; ++i) diff[i] = elevated[i] - rem0[i];
    int rank[kV] = {0, 0, 0, 0};
    for (int i = 0; i < kD; ++i) {
        for (int j = i + 1; j <= kD; ++j) {
            const int less = diff[i] < diff[j] ? 1 : 0;
            rank[i] += less;
            rank[j] += 1 - less;
        }
    }
    // If the rounded point is off the plane (sum != 0), move it back.
    const int isum = static_cast<int>(sum);
    for (int i = 0; i <= kD; ++i) {
        rank[i] += isum;
        const int wrap = (rank[i] < 0 ? kD + 1 : 0) - (rank[i] > kD ? kD + 1 : 0);
        rank[i] += wrap;
        rem0[i] += static_cast<float>(wrap);
    }

    // Barycentric coordinates (Adams et al. 2010 p. 10).
    float bary[kD + 2] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    for (int i = 0; i <= kD; ++i) {
        const float v = (elevated[i] - rem0[i]) * kDown;  // rem0 may have moved: recompute
        bary[kD - rank[i]] += v;
        bary[kD - rank[i] + 1] -= v;
    }
    bary[0] += 1.0f + bary[kD + 1];

    // Vertex r of the simplex: remainder-0 point plus the canonical simplex's vertex r,
    // permuted by rank; canonical[r][j] = r for j <= d - r, else r - (d + 1).
    for (int r = 0; r <= kD; ++r) {
        for (int i = 0; i < kD; ++i) {
            const int canonical = rank[i] <= kD - r ? r : r - (kD + 1);
            out.key[r][i] = static_cast<int>(rem0[i]) + canonical;
        }
        out.weight[r] = bary[r];
    }
}

bool PermutohedralLattice::Build(const LatticeFeatures& features, bool blur, int max_vertices) {
    blur_ = blur;
    complete_ = true;
    elevation_ = ElevationFor(blur);
    std::size_t expected = static_cast<std::size_t>(features.rows()) * kV;
    if (max_vertices >= 0)
        expected = std::min(expected, static_cast<std::size_t>(max_vertices) + 1);
    table_ = LatticeHashTable(expected);
    vertex_.clear();
    weights_.clear();
    return Insert(features, max_vertices);
}

bool PermutohedralLattice::AddPoints(const LatticeFeatures& features, int max_vertices) {
    RequireComplete("AddPoints");
    return Insert(features, max_vertices);
}

void PermutohedralLattice::RequireComplete(const char* what) const {
    if (!complete_) {
        throw std::logic_error(std::string("PermutohedralLattice::") + what +
                               ": lattice is incomplete (stopped at max_vertices)");
    }
}

bool PermutohedralLattice::Insert(const LatticeFeatures& features, int max_vertices) {
    const std::int64_t n = features.rows();
    const std::int64_t first_point = NumPoints();
    vertex_.resize(static_cast<std::size_t>(first_point + n) * kV);
    weights_.resize(static_cast<std::size_t>(first_point + n) * kV);
    auto insert = [&](std::int64_t i, const SimplexEmbedding& e) {
        const std::size_t base = static_cast<std::size_t>(first_point + i) * kV;
        for (int r = 0; r < kV; ++r) {
            vertex_[base + r] = table_.FindOrInsert(e.key[r]);
            weights_[base + r] = e.weight[r];
        }
    };
    if (max_vertices >= 0 || n < kParallelMin) {
        SimplexEmbedding e;
        for (std::int64_t i = 0; i < n; ++i) {
            Embed(features.row(i).data(), elevation_, e);
            insert(i, e);
            if (max_vertices >= 0 && NumVertices() > max_vertices) {
                complete_ = false;
                return false;
            }
        }
        return true;
    }
    // Embedding is per point and pure; hashing stays serial so vertex ids are deterministic.
    std::vector<SimplexEmbedding> embedded(static_cast<std::size_t>(n));
    bool failed = false;
#pragma omp parallel for schedule(static) reduction(|| : failed)
    for (std::int64_t i = 0; i < n; ++i) {
        try {
            Embed(features.row(i).data(), elevation_, embedded[static_cast<std::size_t>(i)]);
        } catch (const std::runtime_error&) {
            failed = true;
        }
    }
    if (failed) {
        throw std::runtime_error(
            "permutohedral lattice: a feature is non-finite or too large for the kernel width");
    }
    for (std::int64_t i = 0; i < n; ++i) insert(i, embedded[static_cast<std::size_t>(i)]);
    return true;
}

LatticeValues PermutohedralLattice::Splat(const LatticeValues& point_values, int begin,
                                          int end) const {
    if (point_values.rows() < end || begin < 0 || begin > end || end > NumPoints()) {
        throw std::invalid_argument("PermutohedralLattice::Splat: rows [" + std::to_string(begin) +
                                    ", " + std::to_string(end) + ") out of range");
    }
    return SplatBlock(point_values.middleRows(begin, end - begin), begin);
}

LatticeValues PermutohedralLattice::SplatBlock(const LatticeValues& block, int begin) const {
    RequireComplete("Splat");
    const Eigen::Index width = block.cols();
    if (begin < 0 || begin + block.rows() > NumPoints()) {
        throw std::invalid_argument("PermutohedralLattice::SplatBlock: block out of range");
    }
    LatticeValues vertex_values = LatticeValues::Zero(NumVertices(), width);
    for (Eigen::Index k = 0; k < block.rows(); ++k) {
        const std::size_t base = static_cast<std::size_t>(begin + k) * kV;
        for (int r = 0; r < kV; ++r) {
            const float w = weights_[base + r];
            float* dst = vertex_values.row(vertex_[base + r]).data();
            const float* src = block.row(k).data();
            for (Eigen::Index c = 0; c < width; ++c) dst[c] += w * src[c];
        }
    }
    return vertex_values;
}

void PermutohedralLattice::Blur(LatticeValues& vertex_values) const {
    if (!blur_) throw std::logic_error("PermutohedralLattice::Blur: lattice built without blur");
    RequireComplete("Blur");
    const int m = NumVertices();
    const Eigen::Index width = vertex_values.cols();
    // Neighbours of vertex i along axis j: key -/+ 1 on every coordinate but j, which moves
    // by +/- d (the implied last coordinate when j == d).
    std::vector<int> neighbours(static_cast<std::size_t>(2 * kV * m));
    for (int j = 0; j <= kD; ++j) {
        for (int i = 0; i < m; ++i) {
            const int* key = table_.KeyOf(i);
            int n1[kD];
            int n2[kD];
            for (int k = 0; k < kD; ++k) {
                n1[k] = key[k] - 1;
                n2[k] = key[k] + 1;
            }
            if (j < kD) {
                n1[j] = key[j] + kD;
                n2[j] = key[j] - kD;
            }
            const std::size_t at = 2 * (static_cast<std::size_t>(j) * m + i);
            neighbours[at] = table_.Find(n1);
            neighbours[at + 1] = table_.Find(n2);
        }
    }
    // One Jacobi sweep per axis: v <- v + 1/2 (v- + v+).
    LatticeValues next(m, width);
    for (int j = 0; j <= kD; ++j) {
        for (int i = 0; i < m; ++i) {
            const std::size_t at = 2 * (static_cast<std::size_t>(j) * m + i);
            const int a = neighbours[at];
            const int b = neighbours[at + 1];
            for (Eigen::Index c = 0; c < width; ++c) {
                const float va = a >= 0 ? vertex_values(a, c) : 0.0f;
                const float vb = b >= 0 ? vertex_values(b, c) : 0.0f;
                next(i, c) = vertex_values(i, c) + 0.5f * (va + vb);
            }
        }
        vertex_values.swap(next);
    }
}

void PermutohedralLattice::Slice(const LatticeValues& vertex_values, int begin, int end,
                                 LatticeValues& out) const {
    RequireComplete("Slice");
    if (begin < 0 || begin > end || end > NumPoints() || vertex_values.rows() != NumVertices()) {
        throw std::invalid_argument("PermutohedralLattice::Slice: bad range or vertex values");
    }
    const Eigen::Index width = vertex_values.cols();
    const float alpha = SliceNormalisation();
    out.setZero(end - begin, width);
#pragma omp parallel for schedule(static) if (end - begin >= kParallelMin)
    for (int p = begin; p < end; ++p) {
        float* dst = out.row(p - begin).data();
        const std::size_t base = static_cast<std::size_t>(p) * kV;
        for (int r = 0; r < kV; ++r) {
            const float w = weights_[base + r] * alpha;
            const float* src = vertex_values.row(vertex_[base + r]).data();
            for (Eigen::Index c = 0; c < width; ++c) dst[c] += w * src[c];
        }
    }
}

void PermutohedralLattice::SliceAt(const LatticeFeatures& queries,
                                   const LatticeValues& vertex_values, LatticeValues& out) const {
    if (blur_) {
        throw std::logic_error("PermutohedralLattice::SliceAt: needs a lattice built without blur");
    }
    RequireComplete("SliceAt");
    if (vertex_values.rows() != NumVertices()) {
        throw std::invalid_argument("PermutohedralLattice::SliceAt: vertex values do not match");
    }
    const std::int64_t n = queries.rows();
    const Eigen::Index width = vertex_values.cols();
    const float alpha = SliceNormalisation();
    out.setZero(n, width);
    bool failed = false;
#pragma omp parallel for schedule(static) if (n >= kParallelMin) reduction(|| : failed)
    for (std::int64_t q = 0; q < n; ++q) {
        SimplexEmbedding e;
        try {
            Embed(queries.row(q).data(), elevation_, e);
        } catch (const std::runtime_error&) {
            failed = true;
            continue;
        }
        float* dst = out.row(q).data();
        for (int r = 0; r < kV; ++r) {
            const int v = table_.Find(e.key[r]);
            if (v < 0) continue;  // an absent vertex holds 0: adding w * 0 changes nothing
            const float w = e.weight[r] * alpha;
            const float* src = vertex_values.row(v).data();
            for (Eigen::Index c = 0; c < width; ++c) dst[c] += w * src[c];
        }
    }
    if (failed) {
        throw std::runtime_error(
            "permutohedral lattice: a query is non-finite or too large for the kernel width");
    }
}

LatticeValues PermutohedralLattice::Filter(const LatticeValues& point_values) const {
    LatticeValues vertex_values = Splat(point_values, 0, NumPoints());
    if (blur_) Blur(vertex_values);
    LatticeValues out;
    Slice(vertex_values, 0, NumPoints(), out);
    return out;
}

}  // namespace regbench
