#include "protocols/pair_hash.hpp"

#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstring>

namespace regbench {
namespace {

/// FNV-1a, 64 bit: simple, stable and fast enough for a few MB of doubles.
class Fnv1a64 {
public:
    void Byte(std::uint8_t b) {
        h_ ^= b;
        h_ *= 1099511628211ull;
    }
    /// Little-endian bytes of v, whatever the host's byte order.
    void U64(std::uint64_t v) {
        for (int i = 0; i < 8; ++i) Byte(static_cast<std::uint8_t>(v >> (8 * i)));
    }
    void Double(double d) {
        std::uint64_t bits = 0;
        std::memcpy(&bits, &d, sizeof(bits));
        U64(bits);
    }
    void String(const std::string& s) {
        U64(s.size());
        for (unsigned char c : s) Byte(c);
    }
    std::uint64_t value() const { return h_; }

private:
    std::uint64_t h_ = 1469598103934665603ull;
};

void HashCloud(Fnv1a64& h, const PointCloud& cloud) {
    h.U64(static_cast<std::uint64_t>(cloud.rows()));
    for (Eigen::Index i = 0; i < cloud.rows(); ++i) {
        for (Eigen::Index c = 0; c < cloud.cols(); ++c) h.Double(cloud(i, c));
    }
}

void HashLabels(Fnv1a64& h, const Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1>& labels) {
    h.U64(static_cast<std::uint64_t>(labels.size()));
    for (Eigen::Index i = 0; i < labels.size(); ++i) h.Byte(labels[i]);
}

}  // namespace

std::string PairSetContentHash(const PairSet& set) {
    Fnv1a64 h;
    h.U64(set.pairs.size());
    for (const Pair& p : set.pairs) {
        HashCloud(h, p.source);
        HashCloud(h, p.target);
        for (int r = 0; r < 4; ++r) {
            for (int c = 0; c < 4; ++c) h.Double(p.T_gt(r, c));
        }
        HashLabels(h, p.source_overlap);
        HashLabels(h, p.target_overlap);
        h.String(p.shape);
        h.String(p.category);
    }
    char hex[17];
    std::snprintf(hex, sizeof(hex), "%016" PRIx64, h.value());
    return std::string("fnv1a64:") + hex;
}

}  // namespace regbench
