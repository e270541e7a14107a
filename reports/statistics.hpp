#pragma once
// Small, dependency-free statistics for the reports: location, spread, seeded bootstrap CIs
// and the Wilcoxon signed-rank test used by `regbench compare`.
#include <cstdint>
#include <string>
#include <vector>

namespace regbench {

/// Mean; NaN for an empty sample.
double SampleMean(const std::vector<double>& v);

/// Median (mean of the two middle values for an even count); NaN for an empty sample.
double SampleMedian(std::vector<double> v);

/// The q-quantile (q in [0, 1]) by linear interpolation between order statistics: with the
/// values sorted, h = q (n - 1) and x[floor h] + (h - floor h) (x[floor h + 1] - x[floor h])
/// (numpy.quantile's default, method="linear"; q = 0.5 is SampleMedian). NaN when empty.
double SampleQuantile(std::vector<double> v, double q);

/// Sample standard deviation (n - 1 denominator, as numpy's std(ddof=1)); 0 below two values.
double SampleStd(const std::vector<double>& v);

/// The seed every report's bootstrap uses unless told otherwise (`compare --seed`).
constexpr std::uint64_t kDefaultBootstrapSeed = 20230103;

/// A mean with a two-sided percentile-bootstrap confidence interval.
struct BootstrapCi {
    double mean = 0.0;
    double lo = 0.0;
    double hi = 0.0;
};

/// The `samples` means of resamples of `v` drawn with replacement from the stream
/// (seed, stream), sorted ascending: the bootstrap distribution every CI here is read from.
/// Empty when `v` has fewer than two values or `samples` < 2.
std::vector<double> SortedBootstrapMeans(const std::vector<double>& v, int samples,
                                         std::uint64_t seed, std::uint64_t stream);

/// The q-quantile (q in [0, 1]) of ascending values: the value at index q (n - 1) rounded to
/// the nearest, halves to even (numpy.percentile(v, 100 q, method="nearest")); NaN when empty.
double NearestRankQuantile(const std::vector<double>& sorted, double q);

/// The one CI of every report (`report`, the paper tables, the breakdowns, `compare`):
/// percentile bootstrap (Efron) of the mean, `samples` resamples with replacement drawn from
/// the stream (seed, stream), [lo, hi] the NearestRankQuantile of the sorted resampled means at
/// q = (1 - level) / 2 and 1 - q. With fewer than two values lo = hi = mean. The stream
/// should be derived from what is being estimated (StreamId), not from the position in a
/// table, so a CI does not change when rows are reordered.
BootstrapCi BootstrapMean(const std::vector<double>& v, int samples, std::uint64_t seed,
                          std::uint64_t stream, double level = 0.95);

/// The paired test of `report --versus` (method A against method B on the same pairs): one
/// percentile bootstrap of the mean of the per-pair differences d = A - B gives both the 95%
/// CI and the two-sided p-value, so they cannot disagree. From the B = `samples` sorted
/// resampled means m (SortedBootstrapMeans: the same resamples as BootstrapMean) with
/// k = floor(B / 40) (= floor(0.025 B)):
///   CI = [m[k], m[B - 1 - k]]  (for B = 2000 the same order statistics, 50 and 1949, as
///                              BootstrapMean's NearestRankQuantile at 0.025 and 0.975)
///   p  = min(1, 2 min(#{m <= 0}, #{m >= 0}) / B)  (Efron & Tibshirani's achieved significance
///                              level; 0 when no resampled mean reaches 0: p < 1 / B)
/// and, since all are counts, p <= 0.05 exactly when the CI excludes 0 (`differs`).
/// Below two differences there is no test: CI and p are NaN and `differs` is false.
struct PairedBootstrapTest {
    double mean = 0.0;     ///< mean of the differences
    double lo = 0.0;       ///< 95% CI of the mean difference
    double hi = 0.0;
    double p_value = 1.0;  ///< two-sided, from the same resampled means
    bool differs = false;  ///< 0 is outside [lo, hi], i.e. p <= 0.05
};

PairedBootstrapTest PairedBootstrap(const std::vector<double>& d, int samples, std::uint64_t seed,
                                    std::uint64_t stream);

/// The two-sided 95% normal quantile, Phi^-1(0.975) (scipy.stats.norm.ppf(0.975)).
constexpr double kZ95 = 1.959963984540054;

/// The proportion k / n with its 95% Wilson score interval (Wilson 1927), the CI of every
/// rate in the reports (recall, success): mean k / n, [lo, hi] clamped to [0, 1], as
/// scipy.stats.binomtest(k, n).proportion_ci(method="wilson"). NaN everywhere when n = 0.
BootstrapCi WilsonInterval(std::size_t k, std::size_t n);

/// A stable 64-bit stream id for a label such as "cpd/mae_r" (FNV-1a), independent of order.
std::uint64_t StreamId(const std::string& label);

/// Which distribution the Wilcoxon p-value was taken from.
enum class WilcoxonMethod {
    kExact,   ///< exact null distribution of the positive rank sum (n <= 50, no ties)
    kNormal,  ///< normal approximation with tie correction, no continuity correction
};

struct WilcoxonResult {
    std::size_t n = 0;       ///< non-zero differences used
    double statistic = 0.0;  ///< min(R+, R-), as scipy.stats.wilcoxon's two-sided statistic
    double p_value = 1.0;    ///< two-sided; 1 when every difference is zero
    WilcoxonMethod method = WilcoxonMethod::kExact;
};

/// Two-sided Wilcoxon signed-rank test of paired differences `d` against a zero median.
/// Zero differences are dropped (Wilcoxon's convention, scipy's zero_method="wilcox");
/// tied |d| get average ranks. The exact null distribution is used when at most 50 non-zero
/// differences remain and none of their magnitudes tie, else the normal approximation with
/// the tie-corrected variance (scipy.stats.wilcoxon with method="exact" / "approx"; scipy's
/// "auto" keeps the exact table even with ties, which then is only approximate).
WilcoxonResult WilcoxonSignedRank(const std::vector<double>& d);

}  // namespace regbench
