#include "reports/compare.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "core/parse_number.hpp"
#include "reports/row_access.hpp"
#include "reports/statistics.hpp"

namespace regbench {
namespace {

using RowKey = std::tuple<std::string, std::size_t, std::string>;  // (pair file, pair, method)

/// Indexes rows by key; a repeated key is an error because the pairing would be ambiguous.
std::map<RowKey, const ResultRow*> IndexRows(const std::vector<ResultRow>& rows,
                                             const std::string& name) {
    std::map<RowKey, const ResultRow*> index;
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const auto& r = rows[i];
        RowKey key{RowPairFileId(r), r.pair, r.method};
        if (!index.emplace(key, &r).second) {
            throw std::runtime_error(fmt::format(
                "{}: row {} repeats pair {} of method {} (merge shards once, or compare the "
                "files separately)",
                name, i + 1, std::get<1>(key), std::get<2>(key)));
        }
    }
    return index;
}

/// Pair files a set was measured on, as "name (id)" for messages.
std::map<std::string, std::string> PairFiles(const std::vector<ResultRow>& rows) {
    std::map<std::string, std::string> files;
    for (const auto& r : rows) files[RowPairFileId(r)] = r.data.pairs_file;
    return files;
}

std::string Describe(const std::map<std::string, std::string>& files) {
    std::string s;
    for (const auto& [id, name] : files) {
        s += (s.empty() ? "" : ", ") + name;
        if (id.rfind("file:", 0) != 0) s += " (" + id.substr(0, 12) + ")";
    }
    return s;
}

/// Standard normal quantile by bisection on Phi(x) = erfc(-x / sqrt 2) / 2 (to ~1e-12).
double NormalQuantile(double p) {
    double lo = -40.0, hi = 40.0;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

/// Smallest mean worsening detected with probability `power` (see MetricChange::detectable).
double DetectableWorsening(const std::vector<double>& d, double alpha, double power) {
    const double n = static_cast<double>(d.size());
    // The exact test's smallest two-sided p: every difference of one sign, 2 * (1/2)^n.
    if (d.empty() || std::ldexp(2.0, -static_cast<int>(std::min<double>(n, 1000.0))) >= alpha) {
        return std::numeric_limits<double>::infinity();
    }
    const double sd = SampleStd(d);
    if (!(sd > 0.0)) return 0.0;
    const double z = NormalQuantile(1.0 - alpha / 2.0) + NormalQuantile(power);
    return z * sd / std::sqrt(n * 3.0 / M_PI);
}

}  // namespace

std::map<std::string, double> DefaultTolerances() {
    return {{"mae_r", 0.1}, {"mae_t", 0.001}, {"ccd", 0.001}, {"rre", 0.2}, {"rte", 0.002}};
}

int VerdictExitCode(CompareVerdict v) {
    switch (v) {
        case CompareVerdict::kPass:
            return 0;
        case CompareVerdict::kFail:
            return 1;
        case CompareVerdict::kInconclusive:
            return 3;
    }
    return 1;
}

bool CompareResult::Regressed() const {
    for (const auto& c : changes) {
        if (c.regression) return true;
    }
    if (!allow_new_failures) {
        for (const auto& m : calls) {
            if (m.new_failures > 0) return true;
        }
    }
    return false;
}

CompareVerdict CompareResult::Verdict() const {
    if (Regressed()) return CompareVerdict::kFail;
    for (const auto& c : changes) {
        if (c.underpowered) return CompareVerdict::kInconclusive;
    }
    for (const auto& m : calls) {
        if (m.pairs < min_pairs) return CompareVerdict::kInconclusive;
    }
    return CompareVerdict::kPass;
}

namespace {

using MatchedRows = std::vector<std::pair<const ResultRow*, const ResultRow*>>;

/// One method's paired test of one metric over its matched (baseline, candidate) rows.
MetricChange TestMetric(const std::string& method, const std::string& metric,
                        const MatchedRows& pairs, const CompareOptions& o) {
    MetricChange c;
    c.method = method;
    c.metric = metric;
    const auto tol = o.tolerance.find(metric);
    c.tolerance = tol == o.tolerance.end() ? o.default_tolerance : tol->second;
    const MetricField& field = FindMetric(metric);
    std::vector<double> b, n, d;
    for (const auto& [rb, rn] : pairs) {
        const auto vb = field.Of(rb->metrics);
        const auto vn = field.Of(rn->metrics);
        if (!vb || !vn) continue;
        b.push_back(*vb);
        n.push_back(*vn);
        d.push_back(*vn - *vb);
    }
    c.pairs = d.size();
    c.detectable = DetectableWorsening(d, o.alpha, o.power);
    if (d.empty()) {
        c.underpowered = true;
        return c;
    }
    c.base_mean = SampleMean(b);
    c.new_mean = SampleMean(n);
    const BootstrapCi ci =
        BootstrapMean(d, o.bootstrap_samples, o.seed, StreamId(method + "/" + metric));
    c.diff_mean = ci.mean;
    c.ci_lo = ci.lo;
    c.ci_hi = ci.hi;
    c.p_value = WilcoxonSignedRank(d).p_value;
    // Below the exact test's floor nothing is significant: the normal approximation
    // taken for tied differences would call 5 equal shifts p = 0.043.
    c.significant =
        !std::isinf(c.detectable) && c.p_value < o.alpha && (c.ci_lo > 0.0 || c.ci_hi < 0.0);
    c.worse = c.significant && c.diff_mean > 0.0;
    c.regression = c.worse && c.diff_mean > c.tolerance;
    // Conclusive without a regression when the test could detect a worsening of the
    // tolerance's size, or the CI already bounds the worsening by the tolerance; never
    // when the exact test cannot reach alpha at all.
    c.underpowered = !c.regression && (std::isinf(c.detectable) ||
                                       (c.detectable > c.tolerance && c.ci_hi > c.tolerance));
    return c;
}

}  // namespace

CompareResult CompareResults(const std::vector<ResultRow>& base,
                             const std::vector<ResultRow>& candidate, const CompareOptions& o,
                             const std::string& base_name, const std::string& new_name) {
    const auto base_files = PairFiles(base);
    const auto new_files = PairFiles(candidate);
    std::set<std::string> base_ids, new_ids;
    for (const auto& f : base_files) base_ids.insert(f.first);
    for (const auto& f : new_files) new_ids.insert(f.first);
    if (base_ids != new_ids) {
        throw std::runtime_error(fmt::format(
            "{} and {} were measured on different pair files: {} vs {}; compare results of "
            "the same frozen pairs",
            base_name, new_name, Describe(base_files), Describe(new_files)));
    }
    const auto base_index = IndexRows(base, base_name);
    const auto new_index = IndexRows(candidate, new_name);

    CompareResult out;
    out.allow_new_failures = o.allow_new_failures;
    out.min_pairs = o.min_pairs;
    std::vector<std::string> methods;
    std::map<std::string, MatchedRows> matched;
    for (const auto& [key, row] : base_index) {
        const std::string& method = std::get<2>(key);
        const auto it = new_index.find(key);
        if (it == new_index.end()) {
            ++out.base_only;
            continue;
        }
        if (!matched.count(method)) methods.push_back(method);
        matched[method].emplace_back(row, it->second);
        ++out.matched_rows;
        const bool failed_base = row->status != Status::kOk;
        const bool failed_new = it->second->status != Status::kOk;
        out.failures_base += failed_base;
        out.failures_new += failed_new;
        auto calls = std::find_if(out.calls.begin(), out.calls.end(),
                                  [&](const MethodCalls& m) { return m.method == method; });
        if (calls == out.calls.end()) {
            out.calls.push_back(MethodCalls{method});
            calls = out.calls.end() - 1;
        }
        ++calls->pairs;
        calls->failed_base += failed_base;
        calls->failed_new += failed_new;
        calls->new_failures += !failed_base && failed_new;
    }
    out.new_only = new_index.size() - out.matched_rows;
    if (out.matched_rows == 0) {
        throw std::runtime_error(base_name + " and " + new_name + " share no (pair, method) rows");
    }
    for (const auto& method : methods) {
        for (const auto& metric : o.metrics) {
            out.changes.push_back(TestMetric(method, metric, matched[method], o));
        }
    }
    return out;
}

void ParseTolerance(const std::string& text, CompareOptions* o) {
    const auto number = [&](const std::string& s) {
        const std::optional<double> v = ParseNumber<double>(s);
        // inf would switch the gate off (an identity candidate PASSed): finite only.
        if (!v || !std::isfinite(*v) || !(*v >= 0.0)) {
            throw std::invalid_argument("--tolerance: '" + s +
                                        "' is not a finite non-negative number (use e.g. 0.5 or "
                                        "mae_r=0.5,ccd=0.001)");
        }
        return *v;
    };
    if (text.find('=') == std::string::npos) {
        o->default_tolerance = number(text);
        for (auto& [metric, tol] : o->tolerance) tol = o->default_tolerance;
        return;
    }
    auto known = DefaultTolerances();
    for (const auto& m : o->metrics) known.emplace(m, 0.0);
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        const auto eq = item.find('=');
        if (eq == std::string::npos) {
            throw std::invalid_argument("--tolerance: '" + item + "' is not METRIC=VALUE");
        }
        const std::string metric = item.substr(0, eq);
        if (!known.count(metric)) {
            throw std::invalid_argument("--tolerance: '" + metric +
                                        "' is not one of the compared metrics (--metrics)");
        }
        o->tolerance[metric] = number(item.substr(eq + 1));
    }
}

namespace {

/// One line per comparison that could not have found a worsening as large as its tolerance
/// (MAE(R), the paper's headline metric, first), and per method below --min-pairs.
std::string UnderpoweredLines(const CompareResult& r, const CompareOptions& o) {
    std::vector<const MetricChange*> order;
    for (const auto& c : r.changes) {
        if (c.metric == "mae_r") order.push_back(&c);
    }
    for (const auto& c : r.changes) {
        if (c.metric != "mae_r") order.push_back(&c);
    }
    std::string weak;
    for (const MetricChange* change : order) {
        const MetricChange& c = *change;
        if (!c.underpowered) continue;
        weak += std::isinf(c.detectable)
                    ? fmt::format(
                          "- {} {}: {} pairs; the exact Wilcoxon test cannot reach "
                          "p < {:g} with so few pairs (smallest p: {:.3g})\n",
                          c.method, c.metric, c.pairs, o.alpha,
                          c.pairs == 0 ? 1.0 : std::ldexp(2.0, -int(c.pairs)))
                    : fmt::format(
                          "- {} {}: {} pairs detect a worsening of {:.4g} (power {:g}), "
                          "not the tolerance {:g}\n",
                          c.method, c.metric, c.pairs, c.detectable, o.power, c.tolerance);
    }
    for (const auto& m : r.calls) {
        if (m.pairs < r.min_pairs) {
            weak += fmt::format("- {}: {} matched pairs, fewer than --min-pairs {}\n", m.method,
                                m.pairs, r.min_pairs);
        }
    }
    return weak;
}

}  // namespace

std::string FormatCompareMarkdown(const CompareResult& r, const CompareOptions& o) {
    std::string out = fmt::format(
        "{} matched rows ({} only in the baseline, {} only in the candidate); failed calls: "
        "{} -> {}\n\n",
        r.matched_rows, r.base_only, r.new_only, r.failures_base, r.failures_new);
    for (const auto& m : r.calls) {
        if (m.new_failures == 0) continue;
        out += fmt::format(
            "{}: {} call(s) ok in the baseline failed, timed out or crashed in the candidate "
            "({} of {} pairs failed, {} before){}\n",
            m.method, m.new_failures, m.failed_new, m.pairs, m.failed_base,
            r.allow_new_failures ? " (allowed by --allow-new-failures)" : ": FAIL");
    }
    std::string table =
        "| method | metric | pairs | baseline | candidate | change | 95% CI | Wilcoxon p | "
        "tolerance | verdict |\n|---|---|---:|---:|---:|---:|---|---:|---:|---|\n";
    std::size_t shown = 0;
    for (const auto& c : r.changes) {
        if (!c.significant) continue;
        ++shown;
        table += fmt::format(
            "| {} | {} | {} | {:.4g} | {:.4g} | {:+.4g} | [{:+.4g}, {:+.4g}] | {:.2g} | {:g} | "
            "{} |\n",
            c.method, c.metric, c.pairs, c.base_mean, c.new_mean, c.diff_mean, c.ci_lo, c.ci_hi,
            c.p_value, c.tolerance,
            c.regression ? "**REGRESSION**" : (c.worse ? "worse, within tolerance" : "better"));
    }
    if (out.substr(out.size() - 2) != "\n\n") out += "\n";
    out += shown == 0 ? fmt::format(
                            "No significant change (Wilcoxon p < {:g} and a 95% CI "
                            "excluding 0) in any method or metric.\n",
                            o.alpha)
                      : table;
    const std::string weak = UnderpoweredLines(r, o);
    switch (r.Verdict()) {
        case CompareVerdict::kFail:
            // What could not be tested is still said: a FAIL on new failures says nothing
            // about whether the metrics held.
            if (!weak.empty()) {
                out += "\nUnderpowered (the test could not have found a worsening as large as "
                       "the tolerance):\n" + weak;
            }
            out +=
                "\nVerdict: FAIL (a method got significantly worse beyond tolerance, or "
                "calls failed that did not before)\n";
            break;
        case CompareVerdict::kInconclusive:
            out +=
                "\nUnderpowered (no regression found, but the test could not have found one "
                "as large as the tolerance):\n" +
                weak + "\nVerdict: INCONCLUSIVE (use more pairs or a larger --tolerance; exit 3)\n";
            break;
        case CompareVerdict::kPass:
            out += "\nVerdict: PASS\n";
            break;
    }
    return out;
}

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(MethodCalls, method, pairs, failed_base, failed_new,
                                   new_failures)

nlohmann::json CompareToJson(const CompareResult& r, const CompareOptions& o) {
    nlohmann::json changes = nlohmann::json::array();
    for (const auto& c : r.changes) {
        changes.push_back({{"method", c.method},
                           {"metric", c.metric},
                           {"pairs", c.pairs},
                           {"base_mean", c.base_mean},
                           {"new_mean", c.new_mean},
                           {"diff_mean", c.diff_mean},
                           {"ci95", {c.ci_lo, c.ci_hi}},
                           {"wilcoxon_p", c.p_value},
                           {"significant", c.significant},
                           {"worse", c.worse},
                           {"tolerance", c.tolerance},
                           {"detectable", std::isinf(c.detectable) ? nlohmann::json(nullptr)
                                                                   : nlohmann::json(c.detectable)},
                           {"underpowered", c.underpowered},
                           {"regression", c.regression}});
    }
    const CompareVerdict v = r.Verdict();
    return {{"matched_rows", r.matched_rows},
            {"verdict", v == CompareVerdict::kPass   ? "PASS"
                        : v == CompareVerdict::kFail ? "FAIL"
                                                     : "INCONCLUSIVE"},
            {"exit_code", VerdictExitCode(v)},
            {"allow_new_failures", r.allow_new_failures},
            {"min_pairs", r.min_pairs},
            {"power", o.power},
            {"calls", r.calls},
            {"base_only", r.base_only},
            {"new_only", r.new_only},
            {"alpha", o.alpha},
            {"bootstrap_samples", o.bootstrap_samples},
            {"seed", o.seed},
            {"regression", r.Regressed()},
            {"changes", changes}};
}

}  // namespace regbench
