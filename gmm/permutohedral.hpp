#pragma once
// Permutohedral lattice for 3-D features (Adams, Baek, Davis, "Fast High-Dimensional Filtering
// Using the Permutohedral Lattice", Eurographics 2010), as Krähenbühl's implementation (which
// probreg's FilterReg uses) runs it: elevation, enclosing-simplex vertices found by rounding
// and sorting, splat with barycentric weights, an optional [1/2 1 1/2] blur along each of the
// d+1 lattice axes, slice, and the normalisation 1 / (1 + 2^-d).
//
// Precision: float32 throughout, as probreg (its lattice takes Eigen::MatrixXf), with the
// elevation and rounding done in the same float operation order, so the simplex each feature
// falls in and its barycentric weights match probreg's. Splat sums are accumulated in point
// order and the blur is a Jacobi sweep per axis, both as the reference; the only differences
// are the last-ulp rounding of the slice product (we form (b * alpha) * v for every channel)
// and of the blur's 1/2 (float, where the reference's scalar path promotes to double).
//
// Block padding: the reference's SSE build (what probreg's x86-64 wheels run) embeds points
// in blocks of 4 and also inserts the simplex of the zero feature for the padding slots of the
// last block when the point count is not a multiple of 4. Those vertices carry 0 but count in
// the lattice size and relay values during the blur. ReferencePadding() says how many such
// slots there are; a caller that wants the reference's lattice appends that many zero rows
// (one suffices: they share a simplex) with zero values. Checked against Krähenbühl's code:
// identical vertex counts and filter outputs within float rounding on random features.
//
// Deterministic: vertex ids follow first-insertion order, and no result depends on them.
// Thread-safety: const methods may run concurrently; Build/AddPoints may not.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace regbench {

/// Lattice features, one point per row (the caller divides positions by the kernel width).
using LatticeFeatures = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// Values carried by points or lattice vertices, one row each, any number of channels.
using LatticeValues = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Open-addressing hash table from a lattice vertex's first d integer coordinates (the last
/// one is implied: coordinates sum to 0) to a dense vertex id. Linear probing, power-of-two
/// capacity kept at most half full.
class LatticeHashTable {
public:
    static constexpr int kMaxCoordinate = (1 << 20) - 1;  ///< keys pack 3 x 21-bit fields

    explicit LatticeHashTable(std::size_t expected_vertices = 64);
    /// Id of the vertex with these coordinates, inserting it when absent.
    /// Throws std::runtime_error when a coordinate exceeds kMaxCoordinate in magnitude.
    int FindOrInsert(const int key[3]);
    /// Id of the vertex with these coordinates, or -1 when absent (never inserts).
    int Find(const int key[3]) const;
    int size() const { return static_cast<int>(keys_by_id_.size()); }
    /// Coordinates of vertex `id` (3 ints).
    const int* KeyOf(int id) const { return &coords_by_id_[3 * static_cast<std::size_t>(id)]; }

private:
    static std::uint64_t Pack(const int key[3]);
    std::size_t Slot(std::uint64_t packed) const;
    void Grow();
    void SetCapacity(std::size_t capacity);

    std::vector<std::uint64_t> slots_key_;  ///< kEmpty or a packed key
    std::vector<int> slots_id_;
    std::vector<std::uint64_t> keys_by_id_;
    std::vector<int> coords_by_id_;
    std::size_t mask_ = 0;
    int shift_ = 60;
};

/// Where one feature lands: the d+1 vertices of its enclosing simplex and its barycentric
/// weights (non-negative, summing to 1).
struct SimplexEmbedding {
    int key[4][3];    ///< integer lattice coordinates (first d) of each vertex
    float weight[4];  ///< barycentric weight of each vertex
};

class PermutohedralLattice {
public:
    static constexpr int kDim = 3;                      ///< feature dimension d
    static constexpr int kVertices = kDim + 1;          ///< vertices of an enclosing simplex
    static constexpr std::int64_t kParallelMin = 4096;  ///< points below this: one thread

    /// Diagonal of the elevation matrix E (Adams et al. 2010 p. 5), 1/sqrt((i+1)(i+2)),
    /// times the inverse standard deviation of the filter (p. 6): (d+1) sqrt(2/3) when the
    /// blur is used, (d+1) sqrt(1/6) without (then the kernel is a compact tent).
    struct Elevation {
        float scale[kDim];
    };
    static Elevation ElevationFor(bool blur);
    /// Padding slots the reference's SSE build adds after `num_points` points (see above).
    static int ReferencePadding(std::int64_t num_points) {
        return static_cast<int>((kVertices - num_points % kVertices) % kVertices);
    }
    /// Slice normalisation alpha = 1 / (1 + 2^-d) of the reference implementation.
    static float SliceNormalisation();
    /// Elevates one feature and finds its enclosing simplex (Adams et al. 2010 sec. 3-4).
    /// Throws std::runtime_error when the feature is too far out for the integer keys.
    static void Embed(const float feature[kDim], const Elevation& elevation, SimplexEmbedding& out);

    /// Builds the lattice over `features` (point i = row i). `blur` selects the elevation
    /// scale and enables Blur(). With max_vertices >= 0 it stops as soon as the lattice has
    /// more vertices than that and returns false; the lattice is then incomplete (only
    /// NumVertices() > max_vertices is meaningful, the other methods throw). Returns true
    /// when every point went in.
    bool Build(const LatticeFeatures& features, bool blur, int max_vertices = -1);
    /// Appends points (they get ids NumPoints()...), inserting their simplex vertices; same
    /// early stop as Build.
    bool AddPoints(const LatticeFeatures& features, int max_vertices = -1);

    int NumVertices() const { return table_.size(); }
    int NumPoints() const { return static_cast<int>(weights_.size() / kVertices); }
    bool blur() const { return blur_; }

    /// Splats rows [begin, end) of `point_values` (row i = point i) onto the vertices.
    /// Returns NumVertices() x width vertex values.
    LatticeValues Splat(const LatticeValues& point_values, int begin, int end) const;
    /// Splats a block of values that belong to points begin, begin+1, ... (block row k =
    /// point begin+k): lets callers keep only the non-zero rows.
    LatticeValues SplatBlock(const LatticeValues& block, int begin) const;
    /// v <- v + 1/2 (v- + v+) along each of the d+1 axes in turn (missing neighbours are 0).
    /// Throws std::logic_error when the lattice was built without blur.
    void Blur(LatticeValues& vertex_values) const;
    /// out row k = alpha * sum_v b_v * vertex_values(v) for point begin + k, k < end - begin.
    void Slice(const LatticeValues& vertex_values, int begin, int end, LatticeValues& out) const;
    /// Slices at features that are not lattice points. Vertices absent from the lattice count
    /// as 0, which is exactly what inserting the query points with zero values would give when
    /// there is no blur. Throws std::logic_error for a blurred lattice (queries would change
    /// how values spread).
    void SliceAt(const LatticeFeatures& queries, const LatticeValues& vertex_values,
                 LatticeValues& out) const;
    /// Krähenbühl's compute(): splat every row, blur when enabled, slice every row.
    LatticeValues Filter(const LatticeValues& point_values) const;

private:
    bool Insert(const LatticeFeatures& features, int max_vertices);
    void RequireComplete(const char* what) const;

    bool blur_ = true;
    bool complete_ = true;
    Elevation elevation_{};
    LatticeHashTable table_;
    std::vector<int> vertex_;     ///< NumPoints x (d+1) vertex ids
    std::vector<float> weights_;  ///< NumPoints x (d+1) barycentric weights
};

}  // namespace regbench
