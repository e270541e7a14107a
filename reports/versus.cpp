#include "reports/versus.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>
#include <utility>

#include "reports/report.hpp"
#include "reports/row_access.hpp"

namespace regbench {
namespace {

/// Rows of one pair file and Euler convention (the groups `report` never pools).
using GroupKey = std::pair<std::string, EulerConvention>;

/// The rows of `method` by group and pair; a second row of one pair is refused.
std::map<GroupKey, std::map<std::size_t, const ResultRow*>> IndexMethod(
    const std::vector<ResultRow>& rows, const std::string& method) {
    std::map<GroupKey, std::map<std::size_t, const ResultRow*>> index;
    for (const ResultRow* r : RowsOf(rows, method)) {
        auto& by_pair = index[{RowPairFileId(*r), r->euler}];
        if (!by_pair.emplace(r->pair, r).second) {
            throw std::runtime_error(
                fmt::format("method '{}' has two rows of pair {} of {} (several parameter sets or "
                            "unmerged shards; compare one set: report its file alone)",
                            method, r->pair, r->data.pairs_file));
        }
    }
    return index;
}

std::string MethodList(const std::vector<ResultRow>& rows) {
    std::string list;
    for (const auto& m : MethodOrder(rows)) list += (list.empty() ? "'" : ", '") + m + "'";
    return list;
}

VersusMetric TestMetric(const std::vector<std::pair<const ResultRow*, const ResultRow*>>& matched,
                        const std::string& metric, const std::string& stream,
                        const VersusOptions& o) {
    VersusMetric v;
    v.metric = metric;
    const MetricField& field = FindMetric(metric);
    std::vector<double> a, b, d;
    for (const auto& [ra, rb] : matched) {
        const auto va = field.Of(ra->metrics);
        const auto vb = field.Of(rb->metrics);
        if (!va || !vb) continue;
        a.push_back(*va);
        b.push_back(*vb);
        d.push_back(*va - *vb);
        v.wins += *va < *vb;
        v.ties += *va == *vb;
        v.losses += *va > *vb;
    }
    v.pairs = d.size();
    if (d.empty()) return v;
    v.mean_a = SampleMean(a);
    v.mean_b = SampleMean(b);
    const PairedBootstrapTest t = PairedBootstrap(d, o.bootstrap_samples, o.seed, StreamId(stream));
    v.diff_mean = t.mean;
    v.ci_lo = t.lo;
    v.ci_hi = t.hi;
    v.p_value = t.p_value;
    v.differs = t.differs;
    return v;
}

}  // namespace

std::vector<VersusResult> CompareMethods(const std::vector<ResultRow>& rows, const std::string& a,
                                         const std::string& b, const VersusOptions& o) {
    if (a == b) throw std::invalid_argument("--versus names method '" + a + "' twice");
    const auto index_a = IndexMethod(rows, a);
    const auto index_b = IndexMethod(rows, b);
    for (const auto* m : {&a, &b}) {
        if ((m == &a ? index_a : index_b).empty()) {
            throw std::runtime_error("no rows of method '" + *m + "'; the results hold " +
                                     MethodList(rows));
        }
    }
    std::vector<VersusResult> out;
    for (const auto& [key, pairs_a] : index_a) {
        const auto it = index_b.find(key);
        if (it == index_b.end()) continue;
        VersusResult r;
        r.method_a = a;
        r.method_b = b;
        r.data = pairs_a.begin()->second->data;
        r.euler = key.second;
        r.pairs_a = pairs_a.size();
        r.pairs_b = it->second.size();
        std::vector<std::pair<const ResultRow*, const ResultRow*>> matched;
        for (const auto& [pair, row_a] : pairs_a) {
            const auto row_b = it->second.find(pair);
            if (row_b == it->second.end()) continue;
            matched.emplace_back(row_a, row_b->second);
            r.failed_a += row_a->status != Status::kOk;
            r.failed_b += row_b->second->status != Status::kOk;
        }
        r.common = matched.size();
        r.bootstrap_samples = o.bootstrap_samples;
        if (matched.empty()) continue;
        for (const auto& metric : o.metrics) {
            r.metrics.push_back(TestMetric(matched, metric, a + "/" + b + "/" + metric, o));
        }
        out.push_back(std::move(r));
    }
    if (out.empty()) {
        throw std::runtime_error("methods '" + a + "' and '" + b +
                                 "' share no pairs: no pair file and Euler convention holds rows "
                                 "of both (compare rows measured on the same frozen pairs)");
    }
    return out;
}

std::string VersusVerdict(const VersusResult& r, const VersusMetric& m) {
    const std::string diff = r.method_a + " - " + r.method_b;
    if (m.pairs < 2) {
        return fmt::format("{}: no verdict ({} common pair{} with a finite {}; a paired test needs "
                           "two)",
                           m.metric, m.pairs, m.pairs == 1 ? "" : "s", m.metric);
    }
    // p = 0: no resampled mean reached 0, so p is below one resample's share.
    const std::string p = m.p_value == 0.0
                              ? fmt::format("p < {:.2g}", 1.0 / r.bootstrap_samples)
                              : fmt::format("p = {:.4f}", m.p_value);
    const std::string numbers = fmt::format("{} = {:.4g}, 95% CI [{:.4g}, {:.4g}], {}", diff,
                                            m.diff_mean, m.ci_lo, m.ci_hi, p);
    if (!m.differs) {
        return fmt::format("{}: no difference shown between {} and {} ({}; the CI contains 0)",
                           m.metric, r.method_a, r.method_b, numbers);
    }
    const bool a_better = m.diff_mean < 0.0;  // every metric is an error: lower is better
    return fmt::format("{}: {} better than {} ({})", m.metric,
                       a_better ? r.method_a : r.method_b, a_better ? r.method_b : r.method_a,
                       numbers);
}

Table VersusTable(const VersusResult& r) {
    ReportTable described;
    described.data = r.data;
    described.euler = r.euler;
    Table t("versus:" + r.method_a + ":" + r.method_b, r.method_a + " vs " + r.method_b,
            fmt::format("Data: {}. Paired on the {} pairs both ran ({}: {} pairs, {}: {}; failed "
                        "calls among them: {} {}, {} {}, scored as the identity they carry, as "
                        "`report` counts them).",
                        DescribeTable(described), r.common, r.method_a, r.pairs_a, r.method_b,
                        r.pairs_b, r.method_a, r.failed_a, r.method_b, r.failed_b));
    t.row_header = "metric";
    const auto col = [](const std::string& key, const std::string& header, int decimals,
                        CiStyle ci = CiStyle::kHidden) {
        return Column{key, header, CellSource::kMeasured, Better::kNone, decimals, ci};
    };
    t.columns = {col("pairs", "pairs", 0),
                 col("mean_a", r.method_a, 4),
                 col("mean_b", r.method_b, 4),
                 col("diff_mean", r.method_a + " - " + r.method_b, 4),
                 col("diff", "95% CI", 4, CiStyle::kInterval),
                 col("p", "p", 4),
                 col("wins", r.method_a + " better", 0),
                 col("ties", "ties", 0),
                 col("losses", r.method_b + " better", 0)};
    int decimals = 0;  // one per column: the finest of the metrics' own
    for (const auto& m : r.metrics) decimals = std::max(decimals, FindMetric(m.metric).decimals);
    for (const std::size_t c : {1, 2, 3, 4}) t.columns[c].decimals = decimals;
    for (const auto& m : r.metrics) {
        const auto cell = [&](double v) {
            return m.pairs == 0 ? Cell{} : MeasuredCell(v, m.pairs);
        };
        Cell diff = cell(m.diff_mean);
        if (m.pairs >= 2) {
            diff.ci_lo = m.ci_lo;
            diff.ci_hi = m.ci_hi;
        }
        t.AddRow(m.metric, {{"pairs", MeasuredCell(static_cast<double>(m.pairs), m.pairs)},
                            {"mean_a", cell(m.mean_a)},
                            {"mean_b", cell(m.mean_b)},
                            {"diff", diff},
                            {"diff_mean", cell(m.diff_mean)},
                            {"p", m.pairs < 2 ? Cell{} : cell(m.p_value)},
                            {"wins", cell(static_cast<double>(m.wins))},
                            {"ties", cell(static_cast<double>(m.ties))},
                            {"losses", cell(static_cast<double>(m.losses))}});
    }
    t.notes.push_back(
        "Lower is better for every metric; " + r.method_a + " - " + r.method_b + " < 0 favours " +
        r.method_a +
        ". CI and p: one paired bootstrap of the mean difference (" +
        std::to_string(r.bootstrap_samples) +
        " resamples of the pairs; p = 2 x the share of resampled means on the far side of 0, so "
        "p <= 0.05 exactly when the CI excludes 0); ties: equal values.");
    for (const auto& m : r.metrics) t.notes.push_back("Verdict " + VersusVerdict(r, m) + ".");
    return t;
}

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(VersusMetric, metric, pairs, mean_a, mean_b, diff_mean, ci_lo,
                                   ci_hi, p_value, differs, wins, ties, losses)

nlohmann::json VersusToJson(const VersusResult& r) {
    nlohmann::json metrics = nlohmann::json::array();
    for (const auto& m : r.metrics) {
        nlohmann::json j = m;
        j["verdict"] = VersusVerdict(r, m);
        metrics.push_back(std::move(j));
    }
    return {{"method_a", r.method_a},
            {"method_b", r.method_b},
            {"data", r.data},
            {"euler", ToString(r.euler)},
            {"pairs_a", r.pairs_a},
            {"pairs_b", r.pairs_b},
            {"common", r.common},
            {"failed_a", r.failed_a},
            {"failed_b", r.failed_b},
            {"bootstrap_samples", r.bootstrap_samples},
            {"metrics", metrics}};
}

}  // namespace regbench
