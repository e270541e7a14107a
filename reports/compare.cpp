#include "reports/compare.hpp"

#include <fmt/format.h>

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

using RowKey = std::tuple<std::string, long long, std::string>;  // (pair file, pair, method)

/// Indexes rows by key; a repeated key is an error because the pairing would be ambiguous.
std::map<RowKey, const nlohmann::json*> IndexRows(const std::vector<nlohmann::json>& rows,
                                                  const std::string& name) {
    std::map<RowKey, const nlohmann::json*> index;
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const auto& r = rows[i];
        if (!r.contains("pair") || !r.contains("method")) {
            throw std::runtime_error(fmt::format("{}: row {} has no pair or method", name, i + 1));
        }
        RowKey key{RowPairFileId(r), r["pair"].get<long long>(), r["method"].get<std::string>()};
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
std::map<std::string, std::string> PairFiles(const std::vector<nlohmann::json>& rows) {
    std::map<std::string, std::string> files;
    for (const auto& r : rows) files[RowPairFileId(r)] = RowPairFileName(r);
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

}  // namespace

bool CompareResult::Regressed() const {
    for (const auto& c : changes) {
        if (c.regression) return true;
    }
    return false;
}

CompareResult CompareResults(const std::vector<nlohmann::json>& base,
                             const std::vector<nlohmann::json>& candidate,
                             const CompareOptions& o,
                             const std::string& base_name,
                             const std::string& new_name) {
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
    std::vector<std::string> methods;
    std::map<std::string, std::vector<std::pair<const nlohmann::json*, const nlohmann::json*>>>
        matched;
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
        if (RowStatus(*row) != "ok") ++out.failures_base;
        if (RowStatus(*it->second) != "ok") ++out.failures_new;
    }
    out.new_only = new_index.size() - out.matched_rows;
    if (out.matched_rows == 0) {
        throw std::runtime_error(base_name + " and " + new_name + " share no (pair, method) rows");
    }
    for (const auto& method : methods) {
        for (const auto& metric : o.metrics) {
            MetricChange c;
            c.method = method;
            c.metric = metric;
            const auto tol = o.tolerance.find(metric);
            c.tolerance = tol == o.tolerance.end() ? o.default_tolerance : tol->second;
            std::vector<double> b, n, d;
            for (const auto& [rb, rn] : matched[method]) {
                const auto vb = RowMetric(*rb, metric);
                const auto vn = RowMetric(*rn, metric);
                if (!vb || !vn) continue;
                b.push_back(*vb);
                n.push_back(*vn);
                d.push_back(*vn - *vb);
            }
            c.pairs = d.size();
            if (d.empty()) continue;
            c.base_mean = SampleMean(b);
            c.new_mean = SampleMean(n);
            const BootstrapCi ci =
                BootstrapMean(d, o.bootstrap_samples, o.seed, StreamId(method + "/" + metric));
            c.diff_mean = ci.mean;
            c.ci_lo = ci.lo;
            c.ci_hi = ci.hi;
            c.p_value = WilcoxonSignedRank(d).p_value;
            c.significant = c.p_value < o.alpha && (c.ci_lo > 0.0 || c.ci_hi < 0.0);
            c.worse = c.significant && c.diff_mean > 0.0;
            c.regression = c.worse && c.diff_mean > c.tolerance;
            out.changes.push_back(c);
        }
    }
    return out;
}

void ParseTolerance(const std::string& text, CompareOptions* o) {
    const auto number = [&](const std::string& s) {
        const std::optional<double> v = ParseNumber<double>(s);
        if (!v || !(*v >= 0.0)) {
            throw std::invalid_argument("--tolerance: '" + s +
                                        "' is not a non-negative number (use e.g. 0.5 or "
                                        "mae_r=0.5,ccd=0.001)");
        }
        return *v;
    };
    if (text.find('=') == std::string::npos) {
        o->default_tolerance = number(text);
        return;
    }
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        const auto eq = item.find('=');
        if (eq == std::string::npos) {
            throw std::invalid_argument("--tolerance: '" + item + "' is not METRIC=VALUE");
        }
        o->tolerance[item.substr(0, eq)] = number(item.substr(eq + 1));
    }
}

std::string FormatCompareMarkdown(const CompareResult& r, const CompareOptions& o) {
    std::string out = fmt::format(
        "{} matched rows ({} only in the baseline, {} only in the candidate); failed calls: "
        "{} -> {}\n\n",
        r.matched_rows, r.base_only, r.new_only, r.failures_base, r.failures_new);
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
    out += shown == 0 ? fmt::format(
                            "No significant change (Wilcoxon p < {:g} and a 95% CI "
                            "excluding 0) in any method or metric.\n",
                            o.alpha)
                      : table;
    out += r.Regressed() ? "\nVerdict: FAIL (a method got significantly worse beyond tolerance)\n"
                         : "\nVerdict: PASS\n";
    return out;
}

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
                           {"regression", c.regression}});
    }
    return {{"matched_rows", r.matched_rows},
            {"base_only", r.base_only},
            {"new_only", r.new_only},
            {"alpha", o.alpha},
            {"bootstrap_samples", o.bootstrap_samples},
            {"seed", o.seed},
            {"regression", r.Regressed()},
            {"changes", changes}};
}

}  // namespace regbench
