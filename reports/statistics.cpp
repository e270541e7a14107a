#include "reports/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/rng.hpp"

namespace regbench {

double SampleMean(const std::vector<double>& v) {
    if (v.empty()) return std::nan("");
    return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

double SampleMedian(std::vector<double> v) {
    if (v.empty()) return std::nan("");
    std::sort(v.begin(), v.end());
    const std::size_t mid = v.size() / 2;
    return v.size() % 2 == 1 ? v[mid] : 0.5 * (v[mid - 1] + v[mid]);
}

double SampleQuantile(std::vector<double> v, double q) {
    if (v.empty()) return std::nan("");
    std::sort(v.begin(), v.end());
    const double h = q * static_cast<double>(v.size() - 1);
    const auto lo = static_cast<std::size_t>(std::floor(h));
    if (lo + 1 >= v.size()) return v.back();
    return v[lo] + (h - static_cast<double>(lo)) * (v[lo + 1] - v[lo]);
}

double SampleStd(const std::vector<double>& v) {
    if (v.size() < 2) return 0.0;
    const double m = SampleMean(v);
    double s = 0.0;
    for (double x : v) s += (x - m) * (x - m);
    return std::sqrt(s / static_cast<double>(v.size() - 1));
}

std::vector<double> SortedBootstrapMeans(const std::vector<double>& v, int samples,
                                         std::uint64_t seed, std::uint64_t stream) {
    if (v.size() < 2 || samples < 2) return {};
    auto rng = MakePairRng(seed, stream);
    std::vector<double> means(static_cast<std::size_t>(samples));
    for (auto& m : means) {
        double s = 0.0;
        for (std::size_t i = 0; i < v.size(); ++i) s += v[UniformIndex(rng, v.size())];
        m = s / static_cast<double>(v.size());
    }
    std::sort(means.begin(), means.end());
    return means;
}

double NearestRankQuantile(const std::vector<double>& sorted, double q) {
    if (sorted.empty()) return std::nan("");
    // nearbyint rounds halves to even (the default rounding mode), as numpy's "nearest" does.
    const double at = std::nearbyint(q * static_cast<double>(sorted.size() - 1));
    return sorted[static_cast<std::size_t>(std::clamp(at, 0.0, double(sorted.size() - 1)))];
}

BootstrapCi BootstrapMean(const std::vector<double>& v, int samples, std::uint64_t seed,
                          std::uint64_t stream, double level) {
    BootstrapCi e;
    e.mean = SampleMean(v);
    e.lo = e.hi = e.mean;
    const std::vector<double> means = SortedBootstrapMeans(v, samples, seed, stream);
    if (means.empty()) return e;
    const double tail = 0.5 * (1.0 - level);
    e.lo = NearestRankQuantile(means, tail);
    e.hi = NearestRankQuantile(means, 1.0 - tail);
    return e;
}

PairedBootstrapTest PairedBootstrap(const std::vector<double>& d, int samples, std::uint64_t seed,
                                    std::uint64_t stream) {
    PairedBootstrapTest t;
    t.mean = SampleMean(d);
    const std::vector<double> means = SortedBootstrapMeans(d, samples, seed, stream);
    if (means.empty()) {
        t.lo = t.hi = t.p_value = std::nan("");
        return t;
    }
    const std::size_t b = means.size();
    const std::size_t k = b / 40;  // floor(0.025 B): the 2.5% tail in whole resamples
    t.lo = means[k];
    t.hi = means[b - 1 - k];
    const auto at_most_zero = static_cast<std::size_t>(
        std::upper_bound(means.begin(), means.end(), 0.0) - means.begin());
    const auto below_zero = static_cast<std::size_t>(
        std::lower_bound(means.begin(), means.end(), 0.0) - means.begin());
    const std::size_t tail = std::min(at_most_zero, b - below_zero);
    t.p_value = std::min(1.0, 2.0 * static_cast<double>(tail) / static_cast<double>(b));
    // m[k] > 0 iff #{m <= 0} <= k; m[B-1-k] < 0 iff #{m >= 0} <= k; and 2 tail / B <= 0.05
    // iff tail <= floor(B / 40) = k: the CI and p agree by construction.
    t.differs = tail <= k;
    return t;
}

BootstrapCi WilsonInterval(std::size_t k, std::size_t n) {
    BootstrapCi e;
    if (n == 0) {
        e.mean = e.lo = e.hi = std::nan("");
        return e;
    }
    const double nn = static_cast<double>(n);
    const double p = static_cast<double>(k) / nn;
    const double z2 = kZ95 * kZ95;
    const double centre = (p + z2 / (2.0 * nn)) / (1.0 + z2 / nn);
    const double half =
        kZ95 / (1.0 + z2 / nn) * std::sqrt(p * (1.0 - p) / nn + z2 / (4.0 * nn * nn));
    e.mean = p;
    e.lo = std::max(0.0, centre - half);
    e.hi = std::min(1.0, centre + half);
    return e;
}

std::uint64_t StreamId(const std::string& label) {
    std::uint64_t h = 1469598103934665603ULL;
    for (unsigned char c : label) {
        h ^= c;
        h *= 1099511628211ULL;
    }
    return h;
}

namespace {

/// Average ranks (1-based) of |d|; `tied` reports whether any magnitudes tie, and
/// `tie_term` accumulates sum(t^3 - t) over tie groups for the variance correction.
std::vector<double> AbsRanks(const std::vector<double>& d, bool* tied, double* tie_term) {
    std::vector<std::size_t> order(d.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return std::abs(d[a]) < std::abs(d[b]); });
    std::vector<double> ranks(d.size());
    *tied = false;
    *tie_term = 0.0;
    for (std::size_t i = 0; i < order.size();) {
        std::size_t j = i;
        while (j + 1 < order.size() && std::abs(d[order[j + 1]]) == std::abs(d[order[i]])) ++j;
        const double avg = 0.5 * static_cast<double>(i + j) + 1.0;
        for (std::size_t k = i; k <= j; ++k) ranks[order[k]] = avg;
        const double t = static_cast<double>(j - i + 1);
        if (t > 1) {
            *tied = true;
            *tie_term += t * t * t - t;
        }
        i = j + 1;
    }
    return ranks;
}

/// Number of sign assignments of ranks 1..n giving each positive rank sum 0..n(n+1)/2.
/// Counts stay below 2^50, exact in doubles.
std::vector<double> SignedRankCounts(std::size_t n) {
    const std::size_t max_sum = n * (n + 1) / 2;
    std::vector<double> c(max_sum + 1, 0.0);
    c[0] = 1.0;
    for (std::size_t r = 1; r <= n; ++r) {
        for (std::size_t s = max_sum; s >= r; --s) c[s] += c[s - r];
    }
    return c;
}

}  // namespace

WilcoxonResult WilcoxonSignedRank(const std::vector<double>& diffs) {
    std::vector<double> d;
    for (double x : diffs) {
        if (x != 0.0) d.push_back(x);
    }
    WilcoxonResult out;
    out.n = d.size();
    if (d.empty()) return out;  // nothing changed: no evidence of a shift
    bool tied = false;
    double tie_term = 0.0;
    const std::vector<double> ranks = AbsRanks(d, &tied, &tie_term);
    double r_plus = 0.0, r_minus = 0.0;
    for (std::size_t i = 0; i < d.size(); ++i) (d[i] > 0 ? r_plus : r_minus) += ranks[i];
    out.statistic = std::min(r_plus, r_minus);
    const double n = static_cast<double>(d.size());
    if (d.size() <= 50 && !tied) {
        // Two-sided exact p: twice the smaller tail of R+'s null distribution, capped at 1.
        out.method = WilcoxonMethod::kExact;
        const std::vector<double> counts = SignedRankCounts(d.size());
        const double total = std::ldexp(1.0, static_cast<int>(d.size()));
        const auto rp = static_cast<std::size_t>(std::lround(r_plus));
        if (2 * rp == counts.size() - 1) {
            out.p_value = 1.0;
            return out;
        }
        double less = 0.0, greater = 0.0;
        for (std::size_t s = 0; s < counts.size(); ++s) {
            if (s <= rp) less += counts[s];
            if (s >= rp) greater += counts[s];
        }
        out.p_value = std::min(1.0, 2.0 * std::min(less, greater) / total);
        return out;
    }
    out.method = WilcoxonMethod::kNormal;
    const double mean = n * (n + 1.0) / 4.0;
    const double var = (n * (n + 1.0) * (2.0 * n + 1.0) - 0.5 * tie_term) / 24.0;
    const double z = (out.statistic - mean) / std::sqrt(var);
    out.p_value = std::min(1.0, std::erfc(std::abs(z) / std::sqrt(2.0)));
    return out;
}

}  // namespace regbench
