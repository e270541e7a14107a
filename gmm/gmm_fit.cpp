#include "gmm/gmm_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "core/rng.hpp"
#include "gmm/simd_exp.hpp"

namespace regbench {
namespace {

constexpr double kLog2Pi = 1.8378770664093454836;
/// sklearn adds 10 machine epsilons to every component mass so that empty ones divide safely.
constexpr double kMassFloor = 10.0 * std::numeric_limits<double>::epsilon();
/// Below this many point-component pairs the loops stay on one thread.
constexpr long kMinParallelPairs = 200000;
/// Components per M-step work item (a multiple of the SIMD width).
constexpr long kComponentBlock = 64;

/// Points in structure-of-arrays form so inner loops over points vectorise.
struct Soa {
    std::vector<double> x, y, z;
    explicit Soa(const PointCloud& P)
        : x(static_cast<size_t>(P.rows())),
          y(static_cast<size_t>(P.rows())),
          z(static_cast<size_t>(P.rows())) {
        for (Eigen::Index i = 0; i < P.rows(); ++i) {
            x[static_cast<size_t>(i)] = P(i, 0);
            y[static_cast<size_t>(i)] = P(i, 1);
            z[static_cast<size_t>(i)] = P(i, 2);
        }
    }
};

/// d[i] = min(d[i], |p_i - c|^2); returns sum_i d[i] (k-means++ potential with candidate c).
REGBENCH_SIMD_CLONES double MinDistancesTo(const double* px, const double* py, const double* pz,
                                           long n, double cx, double cy, double cz,
                                           const double* closest, double* out) {
    double pot = 0.0;
#pragma omp simd reduction(+ : pot)
    for (long i = 0; i < n; ++i) {
        const double dx = px[i] - cx, dy = py[i] - cy, dz = pz[i] - cz;
        const double d = dx * dx + dy * dy + dz * dz;
        const double m = d < closest[i] ? d : closest[i];
        out[i] = m;
        pot += m;
    }
    return pot;
}

/// Index of the nearest center (first on ties) and its squared distance: a vectorised pass
/// for the distances and their minimum, then a scan for the first index that attains it.
REGBENCH_SIMD_CLONES int NearestCenter(double x, double y, double z, const double* cx,
                                       const double* cy, const double* cz, long k, double* scratch,
                                       double* best_d2) {
    double best = std::numeric_limits<double>::infinity();
#pragma omp simd reduction(min : best)
    for (long j = 0; j < k; ++j) {
        const double dx = x - cx[j], dy = y - cy[j], dz = z - cz[j];
        const double d = dx * dx + dy * dy + dz * dz;
        scratch[j] = d;
        best = d < best ? d : best;
    }
    long j = 0;
    while (j + 1 < k && scratch[j] != best) ++j;
    *best_d2 = scratch[j];
    return static_cast<int>(j);
}

/// One E-step row: resp_k = exp(wlp_k - logsumexp(wlp)) with the spherical log density
/// wlp_k = -0.5 (D log 2pi + |x - mu_k|^2 / var_k) - D/2 log var_k + log w_k (sklearn's
/// _estimate_weighted_log_prob). Writes exp(wlp_k - max_k wlp_k) into `row` and the inverse
/// of its sum into `inv_sum` (resp = row * inv_sum, applied in AccumulateRow); returns the
/// log-normaliser log sum_k exp(wlp_k).
REGBENCH_SIMD_CLONES double ResponsibilityRow(double x, double y, double z, const double* mx,
                                              const double* my, const double* mz,
                                              const double* neg_half_prec, const double* log_const,
                                              long k, double* row, double* inv_sum) {
    double max_wlp = -std::numeric_limits<double>::infinity();
#pragma omp simd reduction(max : max_wlp)
    for (long j = 0; j < k; ++j) {
        const double dx = x - mx[j], dy = y - my[j], dz = z - mz[j];
        const double w = (dx * dx + dy * dy + dz * dz) * neg_half_prec[j] + log_const[j];
        row[j] = w;
        max_wlp = w > max_wlp ? w : max_wlp;
    }
    double sum = 0.0;
#pragma omp simd reduction(+ : sum)
    for (long j = 0; j < k; ++j) {
        const double e = ExpClamped(row[j] - max_wlp);
        row[j] = e;
        sum += e;
    }
    *inv_sum = 1.0 / sum;
    return max_wlp + std::log(sum);
}

/// M-step accumulation of one row, r_k = row_k * scale: mass_k += r_k, sum_k += r_k x,
/// sumsq_k += r_k |x|^2.
REGBENCH_SIMD_CLONES void AccumulateRow(const double* row, double scale, long k, double x, double y,
                                        double z, double* mass, double* sx, double* sy, double* sz,
                                        double* sxx) {
    const double xx = x * x + y * y + z * z;
#pragma omp simd
    for (long j = 0; j < k; ++j) {
        const double r = row[j] * scale;
        mass[j] += r;
        sx[j] += r * x;
        sy[j] += r * y;
        sz[j] += r * z;
        sxx[j] += r * xx;
    }
}

/// sklearn _kmeans_plusplus (greedy, 2 + floor(ln k) local trials).
PointCloud KMeansPlusPlus(const PointCloud& X, const Soa& p, int k, std::mt19937_64& rng) {
    const long n = static_cast<long>(X.rows());
    PointCloud centers(k, 3);
    const auto first = static_cast<Eigen::Index>(UniformIndex(rng, static_cast<uint64_t>(n)));
    centers.row(0) = X.row(first);
    std::vector<double> closest(static_cast<size_t>(n), std::numeric_limits<double>::infinity());
    std::vector<double> cand_d(static_cast<size_t>(n)), best_d(static_cast<size_t>(n));
    double pot = MinDistancesTo(p.x.data(), p.y.data(), p.z.data(), n, X(first, 0), X(first, 1),
                                X(first, 2), closest.data(), closest.data());
    const int trials = 2 + static_cast<int>(std::log(static_cast<double>(k)));
    std::vector<double> cumsum(static_cast<size_t>(n));
    for (int c = 1; c < k; ++c) {
        std::partial_sum(closest.begin(), closest.end(), cumsum.begin());
        double best_pot = std::numeric_limits<double>::infinity();
        Eigen::Index best_id = 0;
        for (int t = 0; t < trials; ++t) {
            const double u = UniformReal(rng, 0.0, 1.0) * pot;
            // np.searchsorted(cumsum, u) (side 'left'), clipped to n - 1.
            auto it = std::lower_bound(cumsum.begin(), cumsum.end(), u);
            const auto id = std::min<Eigen::Index>(it - cumsum.begin(), n - 1);
            const double cand_pot =
                MinDistancesTo(p.x.data(), p.y.data(), p.z.data(), n, X(id, 0), X(id, 1), X(id, 2),
                               closest.data(), cand_d.data());
            if (cand_pot < best_pot) {
                best_pot = cand_pot;
                best_id = id;
                best_d.swap(cand_d);
            }
        }
        pot = best_pot;
        closest.swap(best_d);
        centers.row(c) = X.row(best_id);
    }
    return centers;
}

}  // namespace

KMeansResult KMeansPlusPlusLloyd(const PointCloud& X, int k, const KMeansOptions& options,
                                 std::mt19937_64& rng) {
    const long n = static_cast<long>(X.rows());
    if (k < 1 || k > n) {
        throw std::invalid_argument("KMeansPlusPlusLloyd: k = " + std::to_string(k) +
                                    " must be in [1, " + std::to_string(n) + "]");
    }
    const Soa p(X);
    KMeansResult r;
    r.centers = KMeansPlusPlus(X, p, k, rng);
    // sklearn scales tol by the mean per-axis (population) variance of X.
    const Eigen::RowVector3d mean = X.colwise().mean();
    const double tol =
        options.tol * (X.rowwise() - mean).array().square().colwise().sum().mean() / n;
    r.labels.assign(static_cast<size_t>(n), -1);
    std::vector<int> labels_old(static_cast<size_t>(n), -1);
    std::vector<double> d2(static_cast<size_t>(n));
    const bool parallel = static_cast<long>(n) * k >= kMinParallelPairs;
    bool strict = false;
    auto assign = [&](const PointCloud& C) {
        const Soa c(C);
#pragma omp parallel if (parallel)
        {
            std::vector<double> scratch(static_cast<size_t>(k));
#pragma omp for schedule(static)
            for (long i = 0; i < n; ++i) {
                r.labels[static_cast<size_t>(i)] =
                    NearestCenter(p.x[static_cast<size_t>(i)], p.y[static_cast<size_t>(i)],
                                  p.z[static_cast<size_t>(i)], c.x.data(), c.y.data(), c.z.data(),
                                  k, scratch.data(), &d2[static_cast<size_t>(i)]);
            }
        }
    };
    for (r.iterations = 0; r.iterations < options.max_iter;) {
        assign(r.centers);
        ++r.iterations;
        // Center sums, then relocate empty clusters (sklearn _relocate_empty_clusters_dense).
        PointCloud sums = PointCloud::Zero(k, 3);
        std::vector<double> count(static_cast<size_t>(k), 0.0);
        for (long i = 0; i < n; ++i) {
            sums.row(r.labels[static_cast<size_t>(i)]) += X.row(i);
            count[static_cast<size_t>(r.labels[static_cast<size_t>(i)])] += 1.0;
        }
        std::vector<int> empty;
        for (int j = 0; j < k; ++j) {
            if (count[static_cast<size_t>(j)] == 0.0) empty.push_back(j);
        }
        if (!empty.empty()) {
            std::vector<long> order(static_cast<size_t>(n));
            std::iota(order.begin(), order.end(), 0L);
            std::stable_sort(order.begin(), order.end(), [&](long a, long b) {
                return d2[static_cast<size_t>(a)] > d2[static_cast<size_t>(b)];
            });
            for (size_t e = 0; e < empty.size(); ++e) {
                const long far = order[e];
                const int old_id = r.labels[static_cast<size_t>(far)];
                sums.row(old_id) -= X.row(far);
                count[static_cast<size_t>(old_id)] -= 1.0;
                sums.row(empty[e]) = X.row(far);
                count[static_cast<size_t>(empty[e])] = 1.0;
            }
        }
        PointCloud next = sums;
        for (int j = 0; j < k; ++j) {
            if (count[static_cast<size_t>(j)] > 0.0) next.row(j) /= count[static_cast<size_t>(j)];
        }
        const double shift = (next - r.centers).squaredNorm();
        r.centers = next;
        if (r.labels == labels_old) {
            strict = true;
            break;
        }
        if (shift <= tol) break;
        labels_old = r.labels;
    }
    if (!strict) assign(r.centers);  // labels consistent with the final centers
    r.inertia = 0.0;
    for (long i = 0; i < n; ++i) r.inertia += d2[static_cast<size_t>(i)];
    return r;
}

// Long on purpose: it follows sklearn's GaussianMixture.fit (spherical) in its order
// (k-means start, E-step, M-step, lower-bound stop), so the two read side by side; the
// parameter update is a lambda because the start and every M-step share it.
SphericalGmm FitSphericalGmm(const PointCloud& X, const GmmFitOptions& options,
                             std::mt19937_64& rng) {
    const long n = static_cast<long>(X.rows());
    const int k = options.n_components;
    if (k < 1 || k > n) {
        throw std::invalid_argument("FitSphericalGmm: n_components = " + std::to_string(k) +
                                    " must be in [1, " + std::to_string(n) + "]");
    }
    const Soa p(X);
    const size_t ks = static_cast<size_t>(k);
    std::vector<double> mass(ks), sx(ks), sy(ks), sz(ks), sxx(ks);
    SphericalGmm gmm;
    gmm.means.resize(k, 3);
    gmm.weights.resize(k);
    gmm.variances.resize(k);
    // Parameters from accumulated sufficient statistics (sklearn
    // _estimate_gaussian_parameters, 'spherical': var = mean_d(E[x_d^2] - mu_d^2) + reg).
    auto m_step = [&]() {
        double total = 0.0;
        for (size_t j = 0; j < ks; ++j) total += mass[j] + kMassFloor;
        for (size_t j = 0; j < ks; ++j) {
            const double nk = mass[j] + kMassFloor;
            const Eigen::RowVector3d mu(sx[j] / nk, sy[j] / nk, sz[j] / nk);
            const auto jj = static_cast<Eigen::Index>(j);
            gmm.means.row(jj) = mu;
            gmm.variances[jj] = (sxx[j] / nk - mu.squaredNorm()) / 3.0 + options.reg_covar;
            gmm.weights[jj] = nk / total;
        }
    };
    auto clear = [&]() {
        for (auto* v : {&mass, &sx, &sy, &sz, &sxx}) std::fill(v->begin(), v->end(), 0.0);
    };

    // Initialisation: hard responsibilities from k-means labels.
    const KMeansResult km = KMeansPlusPlusLloyd(X, k, options.kmeans, rng);
    gmm.kmeans_iterations = km.iterations;
    clear();
    for (long i = 0; i < n; ++i) {
        const auto j = static_cast<size_t>(km.labels[static_cast<size_t>(i)]);
        const double x = p.x[static_cast<size_t>(i)], y = p.y[static_cast<size_t>(i)],
                     z = p.z[static_cast<size_t>(i)];
        mass[j] += 1.0;
        sx[j] += x;
        sy[j] += y;
        sz[j] += z;
        sxx[j] += x * x + y * y + z * z;
    }
    m_step();

    std::vector<double> resp(static_cast<size_t>(n) * ks);
    std::vector<double> log_norm(static_cast<size_t>(n)), inv_sum(static_cast<size_t>(n));
    std::vector<double> mx(ks), my(ks), mz(ks), neg_half_prec(ks), log_const(ks);
    const bool parallel = n * k >= kMinParallelPairs;
    double lower_bound = -std::numeric_limits<double>::infinity();
    for (gmm.iterations = 1; gmm.iterations <= options.max_iter; ++gmm.iterations) {
        // E-step.
        for (size_t j = 0; j < ks; ++j) {
            const auto jj = static_cast<Eigen::Index>(j);
            mx[j] = gmm.means(jj, 0);
            my[j] = gmm.means(jj, 1);
            mz[j] = gmm.means(jj, 2);
            neg_half_prec[j] = -0.5 / gmm.variances[jj];
            log_const[j] =
                -1.5 * kLog2Pi - 1.5 * std::log(gmm.variances[jj]) + std::log(gmm.weights[jj]);
        }
#pragma omp parallel for schedule(static) if (parallel)
        for (long i = 0; i < n; ++i) {
            const auto is = static_cast<size_t>(i);
            log_norm[is] = ResponsibilityRow(p.x[is], p.y[is], p.z[is], mx.data(), my.data(),
                                             mz.data(), neg_half_prec.data(), log_const.data(), k,
                                             &resp[is * ks], &inv_sum[is]);
        }
        // M-step: threads own blocks of components and add the rows in order, so every sum
        // has the same order for any thread count.
        clear();
        const long blocks = (k + kComponentBlock - 1) / kComponentBlock;
#pragma omp parallel for schedule(static) if (parallel)
        for (long b = 0; b < blocks; ++b) {
            const long j0 = b * kComponentBlock;
            const long len = std::min<long>(kComponentBlock, k - j0);
            const auto j = static_cast<size_t>(j0);
            for (long i = 0; i < n; ++i) {
                const auto is = static_cast<size_t>(i);
                AccumulateRow(&resp[is * ks + j], inv_sum[is], len, p.x[is], p.y[is], p.z[is],
                              &mass[j], &sx[j], &sy[j], &sz[j], &sxx[j]);
            }
        }
        m_step();
        const double previous = lower_bound;
        lower_bound = std::accumulate(log_norm.begin(), log_norm.end(), 0.0) / n;
        if (std::abs(lower_bound - previous) < options.tol) {
            gmm.converged = true;
            break;
        }
    }
    gmm.iterations = std::min(gmm.iterations, options.max_iter);
    gmm.lower_bound = lower_bound;
    return gmm;
}

}  // namespace regbench
