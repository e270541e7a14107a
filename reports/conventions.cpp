#include "reports/conventions.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include "core/enum_names.hpp"
#include "reports/report.hpp"

namespace regbench {

namespace {
constexpr EnumName<ErrorPairs> kErrorPairsNames[] = {{ErrorPairs::kAll, "all"},
                                                     {ErrorPairs::kSuccessful, "successful"}};
constexpr EnumName<RatePer> kRatePerNames[] = {
    {RatePer::kPair, "pair"}, {RatePer::kScene, "scene"}, {RatePer::kCategory, "category"}};
}  // namespace

const char* ToString(ErrorPairs e) { return EnumToString(kErrorPairsNames, e); }

ErrorPairs ParseErrorPairs(const std::string& name) {
    return ParseEnum(kErrorPairsNames, "rre/rte pairs", name);
}

const char* ToString(RatePer r) { return EnumToString(kRatePerNames, r); }

RatePer ParseRatePer(const std::string& name) { return ParseEnum(kRatePerNames, "rates per", name); }

bool SuccessRule::Passes(const PairMetrics& m) const {
    // A NaN compares false: a miss.
    return (std::isinf(mae_r_deg) || m.mae_r < mae_r_deg) && (std::isinf(mae_t) || m.mae_t < mae_t) &&
           (std::isinf(rre_deg) || m.rre < rre_deg) && (std::isinf(rte) || m.rte < rte) &&
           (std::isinf(overlap_rmse) || m.overlap_rmse < overlap_rmse);
}

std::string SuccessRule::Bounds() const {
    std::string out;
    const auto add = [&](const char* name, double bound) {
        if (!std::isinf(bound)) out += fmt::format("{}{}<{:g}", out.empty() ? "" : ",", name, bound);
    };
    add("mae_r", mae_r_deg);
    add("mae_t", mae_t);
    add("rre", rre_deg);
    add("rte", rte);
    add("rmse", overlap_rmse);
    return out;
}

std::string SuccessRule::Header() const {
    if (name == "rre-rte") return "success(" + Bounds() + ")";
    return "success " + name + "(" + Bounds() + ")";
}

const std::vector<SuccessRule>& SuccessRulePresets() {
    static const std::vector<SuccessRule> presets = [] {
        std::vector<SuccessRule> p(4);
        p[0].name = "paper-recall";
        p[0].origin = "the OGMM / DCP code's recall, MAE(R) < 1 deg and MAE(t) < 0.1";
        p[0].mae_r_deg = 1.0;
        p[0].mae_t = 0.1;
        p[1].name = "3dmatch-rmse";
        p[1].origin =
            "3DMatch registration recall: RMSE of the ground-truth correspondences (the source "
            "points labelled overlapping) under the estimate < 0.2 m, as Predator and "
            "GeoTransformer evaluate it";
        p[1].overlap_rmse = 0.2;
        p[2].name = "kitti";
        p[2].origin = "the KITTI odometry success criterion, RRE < 5 deg and RTE < 2 m";
        p[2].rre_deg = 5.0;
        p[2].rte = 2.0;
        p[3].name = "3dmatch-rre-rte";
        p[3].origin = "3DMatch-style RRE < 15 deg and RTE < 0.3 m";
        p[3].rre_deg = 15.0;
        p[3].rte = 0.3;
        return p;
    }();
    return presets;
}

std::vector<std::string> SuccessRuleNames() {
    std::vector<std::string> names = {"rre-rte"};
    for (const auto& p : SuccessRulePresets()) names.push_back(p.name);
    return names;
}

SuccessRule FindSuccessRule(const std::string& name, double rre_deg, double rte,
                            double distance_scale) {
    if (name == "rre-rte") {
        SuccessRule r;
        r.name = name;
        r.origin = "--success-rre / --success-rte";
        r.rre_deg = rre_deg;
        r.rte = rte;
        return r;
    }
    for (SuccessRule p : SuccessRulePresets()) {
        if (p.name != name) continue;
        if (distance_scale != 1.0) {
            p.mae_t *= distance_scale;  // infinity stays infinity
            p.rte *= distance_scale;
            p.overlap_rmse *= distance_scale;
            p.origin += fmt::format("; its distances times the pair file's scale {:g}",
                                    distance_scale);
        }
        return p;
    }
    std::string names;
    for (const auto& n : SuccessRuleNames()) names += (names.empty() ? "" : ", ") + n;
    throw std::invalid_argument("success rule '" + name + "': expected one of " + names);
}

BootstrapCi Rate(const std::vector<bool>& hits, const std::vector<std::string>& groups,
                 RatePer per, int samples, std::uint64_t stream, std::size_t* groups_out) {
    if (per == RatePer::kPair) {
        std::size_t k = 0;
        for (bool h : hits) k += h ? 1 : 0;
        if (groups_out) *groups_out = hits.size();
        return WilsonInterval(k, hits.size());
    }
    // Groups in first-seen order, so the bootstrap's input does not depend on map order.
    std::vector<std::string> order;
    std::map<std::string, std::pair<std::size_t, std::size_t>> count;  // group -> (hits, pairs)
    for (std::size_t i = 0; i < hits.size(); ++i) {
        if (!count.count(groups[i])) order.push_back(groups[i]);
        auto& c = count[groups[i]];
        c.first += hits[i] ? 1 : 0;
        ++c.second;
    }
    std::vector<double> rates;
    for (const auto& g : order) {
        rates.push_back(static_cast<double>(count[g].first) / static_cast<double>(count[g].second));
    }
    if (groups_out) *groups_out = rates.size();
    if (rates.empty()) return {std::nan(""), std::nan(""), std::nan("")};
    return BootstrapMean(rates, samples, kDefaultBootstrapSeed, stream);
}

std::string DescribeConventions(const ReportTable& t, const ReportOptions& given) {
    const ReportOptions o = ForData(given, t.data);  // idempotent
    const SuccessRule rule = SuccessRuleOf(o);
    std::string out = "Conventions: rre/rte averaged over ";
    out += o.rre_rte_over == ErrorPairs::kAll
               ? "all pairs with finite metrics (--rre-rte-over all)"
               : "the pairs the success rule accepts (--rre-rte-over successful; pairs: how many)";
    if (o.rates_per == RatePer::kPair) {
        out += "; rates over pairs, 95% Wilson interval (--rates-per pair)";
    } else {
        const std::size_t groups = t.methods.empty() ? 0 : t.methods.front().rate_groups;
        out += fmt::format(
            "; rates averaged over {} {}s (the pairs' `{}`): each {}'s fraction, then their "
            "mean, 95% bootstrap CI over {}s (--rates-per {})",
            groups, ToString(o.rates_per), o.rates_per == RatePer::kScene ? "shape" : "category",
            ToString(o.rates_per), ToString(o.rates_per), ToString(o.rates_per));
    }
    out += fmt::format("; success rule {}: {} ({}); recall@({:g},{:g}): mae_r < {:g} deg and "
                       "mae_t < {:g} (the OGMM code's recall); a failed call is scored as the identity it "
                       "returns, null metrics count as misses.",
                       rule.name, rule.Bounds(), rule.origin, o.recall_r_deg, o.recall_t,
                       o.recall_r_deg, o.recall_t);
    return out;
}

std::string PaperTableConventions(const std::vector<const ResultRow*>& rows) {
    std::string out =
        "Conventions: every mean over all pairs with finite metrics (a failed call scored as "
        "the identity it returns); MAE(R) the mean absolute Euler-angle error without "
        "wrapping in the rows' convention (the paper's: scipy as_euler('zyx')), MAE(t) the "
        "mean absolute per-axis translation error, CCD clipped at the rows' clip "
        "(docs/metrics.md).";
    if (rows.empty()) return out;
    std::set<double> clips, scales;
    std::map<std::string, std::pair<double, std::size_t>> ccd;  // method: (sum over clip, n)
    for (const ResultRow* r : rows) {
        clips.insert(r->metrics.ccd_clip);
        scales.insert(r->data.scale);
        if (!std::isfinite(r->metrics.ccd)) continue;
        auto& c = ccd[r->method];
        c.first += r->metrics.ccd / r->metrics.ccd_clip;
        ++c.second;
    }
    const auto list = [](const std::set<double>& values) {
        std::string text;
        for (double v : values) text += fmt::format("{}{:g}", text.empty() ? "" : ", ", v);
        return text;
    };
    out += fmt::format(" Thresholds in the data's length unit: CCD clip {}", list(clips));
    out += *clips.begin() == kCcdClip && clips.size() == 1
               ? " (the paper's, for unit-sphere objects)"
               : "";
    if (scales.size() > 1 || *scales.begin() != 1.0) {
        out += fmt::format("; pair file scale {} (`generate --scale`): a clip not given to `run "
                           "--ccd-clip` is 0.1 times it",
                           list(scales));
    }
    out += ".";
    const bool saturated =
        !ccd.empty() && std::all_of(ccd.begin(), ccd.end(), [](const auto& c) {
            return c.second.first / static_cast<double>(c.second.second) >= 0.999 * 2.0;
        });
    if (saturated) {
        out += " Saturated: CCD is at its ceiling 2 x clip for every method, so it ranks nothing "
               "here; give `run --ccd-clip` in the data's units (about 10% of the clouds' "
               "radius).";
    }
    return out;
}

}  // namespace regbench
