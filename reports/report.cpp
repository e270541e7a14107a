#include "reports/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include "core/rng.hpp"

namespace regbench {
namespace {

constexpr std::uint64_t kBootstrapSeed = 20230103;

double Mean(const std::vector<double>& v) {
    if (v.empty()) return std::nan("");
    double s = 0.0;
    for (double x : v) s += x;
    return s / static_cast<double>(v.size());
}

double Median(std::vector<double> v) {
    if (v.empty()) return std::nan("");
    const std::size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
    double m = v[mid];
    if (v.size() % 2 == 0) {
        m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid)));
    }
    return m;
}

/// Percentile bootstrap (Efron): resample pairs with replacement, 2.5 / 97.5 percentiles.
Estimate Bootstrap(const std::vector<double>& v, int samples, std::uint64_t stream) {
    Estimate e;
    e.mean = Mean(v);
    e.lo = e.hi = e.mean;
    if (v.size() < 2 || samples < 2) return e;
    auto rng = MakePairRng(kBootstrapSeed, stream);
    std::vector<double> means(static_cast<std::size_t>(samples));
    for (auto& m : means) {
        double s = 0.0;
        for (std::size_t i = 0; i < v.size(); ++i) s += v[UniformIndex(rng, v.size())];
        m = s / static_cast<double>(v.size());
    }
    std::sort(means.begin(), means.end());
    const auto at = [&](double q) {
        return means[static_cast<std::size_t>(q * static_cast<double>(samples - 1))];
    };
    e.lo = at(0.025);
    e.hi = at(0.975);
    return e;
}

double Metric(const nlohmann::json& row, const char* key) {
    if (!row.contains("metrics") || !row["metrics"].contains(key)) {
        throw std::runtime_error("result row for pair " +
                                 row.value("pair", nlohmann::json()).dump() + ", method " +
                                 row.value("method", std::string("?")) + " has no metrics." + key);
    }
    return row["metrics"][key].get<double>();
}

}  // namespace

std::vector<MethodSummary> Summarize(const std::vector<nlohmann::json>& rows,
                                     const ReportOptions& o) {
    std::vector<std::string> order;
    std::map<std::string, std::vector<const nlohmann::json*>> by_method;
    for (const auto& r : rows) {
        const std::string m = r.at("method").get<std::string>();
        if (!by_method.count(m)) order.push_back(m);
        by_method[m].push_back(&r);
    }
    std::vector<MethodSummary> out;
    for (std::size_t mi = 0; mi < order.size(); ++mi) {
        const auto& group = by_method[order[mi]];
        MethodSummary s;
        s.method = order[mi];
        s.pairs = group.size();
        std::vector<double> mae_r, mae_t, ccd, rre, rte, mse_r, mse_t, chamfer, secs;
        std::size_t recalled = 0, succeeded = 0;
        for (const auto* r : group) {
            if (r->value("status", std::string("failed")) != "ok") ++s.failed;
            mae_r.push_back(Metric(*r, "mae_r"));
            mae_t.push_back(Metric(*r, "mae_t"));
            ccd.push_back(Metric(*r, "ccd"));
            rre.push_back(Metric(*r, "rre"));
            rte.push_back(Metric(*r, "rte"));
            mse_r.push_back(Metric(*r, "mse_r"));
            mse_t.push_back(Metric(*r, "mse_t"));
            chamfer.push_back(Metric(*r, "chamfer"));
            secs.push_back(r->value("seconds", 0.0));
            s.threads = r->value("threads", 1);
            if (mae_r.back() < o.recall_r_deg && mae_t.back() < o.recall_t) ++recalled;
            if (rre.back() < o.success_rre_deg && rte.back() < o.success_rte) ++succeeded;
        }
        const std::uint64_t stream = mi * 8;
        s.mae_r = Bootstrap(mae_r, o.bootstrap_samples, stream + 0);
        s.mae_t = Bootstrap(mae_t, o.bootstrap_samples, stream + 1);
        s.ccd = Bootstrap(ccd, o.bootstrap_samples, stream + 2);
        s.rre = Bootstrap(rre, o.bootstrap_samples, stream + 3);
        s.rte = Bootstrap(rte, o.bootstrap_samples, stream + 4);
        s.rmse_r = std::sqrt(Mean(mse_r));
        s.rmse_t = std::sqrt(Mean(mse_t));
        s.chamfer = Mean(chamfer);
        const double n = static_cast<double>(group.size());
        s.recall = static_cast<double>(recalled) / n;
        s.success = static_cast<double>(succeeded) / n;
        s.median_seconds = Median(secs);
        s.mean_seconds = Mean(secs);
        out.push_back(s);
    }
    return out;
}

std::string DescribeData(const std::vector<nlohmann::json>& rows) {
    std::set<std::string> descriptions;
    for (const auto& r : rows) {
        if (!r.contains("data")) {
            descriptions.insert("unknown data (rows carry no 'data' field)");
            continue;
        }
        const auto& d = r["data"];
        descriptions.insert(
            fmt::format("dataset `{}`, protocol `{}`, pairing `{}`, seed {}, file `{}`",
                        d.value("dataset", "?"), d.value("protocol", "?"), d.value("pairing", "?"),
                        d.value("seed", nlohmann::json()).dump(), d.value("pairs_file", "?")));
    }
    std::string out;
    for (const auto& d : descriptions) out += (out.empty() ? "" : "; ") + d;
    return out;
}

std::string FormatMarkdown(const std::vector<MethodSummary>& ss, const ReportOptions& o) {
    std::string out = fmt::format(
        "| method | pairs | failed | mae_r [deg] | mae_r 95% CI | mae_t | ccd | rre [deg] | rte | "
        "rmse_r | rmse_t | recall@({:g},{:g}) | success(rre<{:g},rte<{:g}) | median s | mean s |\n",
        o.recall_r_deg, o.recall_t, o.success_rre_deg, o.success_rte);
    out += "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const auto& s : ss) {
        out += fmt::format(
            "| {} | {} | {} | {:.4f} | [{:.3f}, {:.3f}] | {:.4f} | {:.4f} | {:.4f} | {:.4f} | "
            "{:.4f} | "
            "{:.4f} | {:.3f} | {:.3f} | {:.5f} | {:.5f} |\n",
            s.method, s.pairs, s.failed, s.mae_r.mean, s.mae_r.lo, s.mae_r.hi, s.mae_t.mean,
            s.ccd.mean, s.rre.mean, s.rte.mean, s.rmse_r, s.rmse_t, s.recall, s.success,
            s.median_seconds, s.mean_seconds);
    }
    return out;
}

std::string FormatCsv(const std::vector<MethodSummary>& ss) {
    std::string out =
        "method,pairs,failed,mae_r,mae_r_lo,mae_r_hi,mae_t,mae_t_lo,mae_t_hi,ccd,ccd_lo,ccd_hi,rre,"
        "rte,rmse_r,rmse_t,chamfer,recall,success,median_seconds,mean_seconds,threads\n";
    for (const auto& s : ss) {
        out += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                           s.method, s.pairs, s.failed, s.mae_r.mean, s.mae_r.lo, s.mae_r.hi,
                           s.mae_t.mean, s.mae_t.lo, s.mae_t.hi, s.ccd.mean, s.ccd.lo, s.ccd.hi,
                           s.rre.mean, s.rte.mean, s.rmse_r, s.rmse_t, s.chamfer, s.recall,
                           s.success, s.median_seconds, s.mean_seconds, s.threads);
    }
    return out;
}

std::string FormatLatex(const std::vector<MethodSummary>& ss, const ReportOptions& o) {
    std::string out = "\\begin{tabular}{lrrrrrr}\n\\toprule\n";
    out += fmt::format(
        "Method & MAE(R) & MAE(t) & CCD & RRE & Recall@({:g},{:g}) & Time (s) \\\\\n\\midrule\n",
        o.recall_r_deg, o.recall_t);
    for (const auto& s : ss) {
        out += fmt::format("{} & {:.4f} & {:.4f} & {:.4f} & {:.4f} & {:.3f} & {:.4f} \\\\\n",
                           s.method, s.mae_r.mean, s.mae_t.mean, s.ccd.mean, s.rre.mean, s.recall,
                           s.median_seconds);
    }
    out += "\\bottomrule\n\\end{tabular}\n";
    return out;
}

nlohmann::json ToJson(const std::vector<MethodSummary>& ss, const ReportOptions& o) {
    nlohmann::json arr = nlohmann::json::array();
    const auto est = [](const Estimate& e) {
        return nlohmann::json{{"mean", e.mean}, {"ci95", {e.lo, e.hi}}};
    };
    for (const auto& s : ss) {
        arr.push_back({{"method", s.method},
                       {"pairs", s.pairs},
                       {"failed", s.failed},
                       {"mae_r", est(s.mae_r)},
                       {"mae_t", est(s.mae_t)},
                       {"ccd", est(s.ccd)},
                       {"rre", est(s.rre)},
                       {"rte", est(s.rte)},
                       {"rmse_r", s.rmse_r},
                       {"rmse_t", s.rmse_t},
                       {"chamfer", s.chamfer},
                       {"recall", s.recall},
                       {"recall_thresholds", {o.recall_r_deg, o.recall_t}},
                       {"success", s.success},
                       {"success_thresholds", {o.success_rre_deg, o.success_rte}},
                       {"median_seconds", s.median_seconds},
                       {"mean_seconds", s.mean_seconds},
                       {"threads", s.threads}});
    }
    return arr;
}

}  // namespace regbench
