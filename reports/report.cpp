#include "reports/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include "core/metrics.hpp"
#include "reports/row_access.hpp"
#include "reports/timing.hpp"
#include "reports/statistics.hpp"

namespace regbench {
namespace {

/// Which pair file a row was computed on: its content hash when the row has one, otherwise
/// (rows written before hashes) the file name with the provenance that identifies it.
std::string DataKey(const DataTag& d) {
    if (!d.content_hash.empty()) return "hash:" + d.content_hash;
    return fmt::format("file:{}|{}|{}|{}|{}", d.pairs_file, d.dataset, d.protocol, d.pairing,
                       d.seed.dump());
}

/// A call's message on one line, at most 200 characters (a note, not a log).
std::string OneLineMessage(std::string text) {
    for (char& c : text) {
        if (c == '\n' || c == '\r' || c == '\t') c = ' ';
    }
    if (text.size() > 200) text = text.substr(0, 197) + "...";
    return text;
}

std::string Where(const ResultRow& r) { return r.origin.empty() ? "(in memory)" : r.origin; }

/// The row's metrics in the convention the report asks for.
PairMetrics MetricsIn(const ResultRow& r, const ReportOptions& o) {
    if (!o.euler || *o.euler == r.euler) return r.metrics;
    if (!r.gt_transform) {
        throw std::runtime_error(fmt::format(
            "{}: row was scored with euler '{}' and stores no ground truth to recompute '{}'; "
            "rescore it: regbench score --pairs PAIRS.h5 --transforms {} --method {} --euler {}",
            Where(r), ToString(r.euler), ToString(*o.euler),
            r.origin.substr(0, r.origin.rfind(':')), r.method, ToString(*o.euler)));
    }
    PairMetrics m = r.metrics;
    const PairMetrics motion = MotionMetrics(*r.gt_transform, r.result.T_target_source, *o.euler);
    m.euler = *o.euler;
    m.mae_r = motion.mae_r;
    m.mse_r = motion.mse_r;
    return m;
}

bool AllFinite(const PairMetrics& m) {
    for (double x : {m.mae_r, m.mae_t, m.mse_r, m.mse_t, m.rre, m.rte, m.ccd, m.chamfer}) {
        if (!std::isfinite(x)) return false;
    }
    return true;
}

/// The CCD clip and Open3D inlier threshold the rows were measured with (one per set: rows
/// measured otherwise are refused naming both), and the means of fitness and inlier RMSE.
void SummarizeMetricOptions(const std::vector<const ResultRow*>& group,
                            const std::vector<PairMetrics>& finite, MethodSummary* s) {
    const PairMetrics& first = group.front()->metrics;
    for (const ResultRow* r : group) {
        if (r->metrics.ccd_clip != first.ccd_clip ||
            r->metrics.inlier_threshold != first.inlier_threshold) {
            throw std::runtime_error(fmt::format(
                "{}: measured with ccd clip {:g} and inlier threshold {:g}, {} with {:g} and {:g}; "
                "report rows measured alike (run --ccd-clip / --inlier-threshold)",
                Where(*r), r->metrics.ccd_clip, r->metrics.inlier_threshold, Where(*group.front()),
                first.ccd_clip, first.inlier_threshold));
        }
    }
    s->ccd_clip = first.ccd_clip;
    s->inlier_threshold = first.inlier_threshold;
    if (s->inlier_threshold <= 0.0) return;
    std::vector<double> fitness, rmse;
    for (const PairMetrics& m : finite) {
        if (std::isfinite(m.fitness)) fitness.push_back(m.fitness);
        if (std::isfinite(m.inlier_rmse)) rmse.push_back(m.inlier_rmse);
    }
    s->fitness = SampleMean(fitness);
    s->inlier_rmse = SampleMean(rmse);
}

/// The scene (`shape`) or category a row's rates group by ("" for per-pair rates); refuses a
/// row whose pair file records none.
std::string RateGroup(const ResultRow& r, RatePer per) {
    if (per == RatePer::kPair) return "";
    const std::string& id = per == RatePer::kScene ? r.shape : r.category;
    if (id.empty()) {
        throw std::runtime_error(fmt::format(
            "{}: the pair file records no {} id for pair {} (its `{}` is empty), so rates "
            "cannot be averaged per {}; use --rates-per pair",
            Where(r), ToString(per), r.pair, per == RatePer::kScene ? "shape" : "category",
            ToString(per)));
    }
    return id;
}

/// CPU median and 95th percentile per call; NaN when the rows recorded no CPU time.
void SummarizeCpuTime(const std::vector<double>& wall, const std::vector<double>& cpu,
                      MethodSummary* s) {
    const bool any_cpu = std::any_of(cpu.begin(), cpu.end(), [](double x) { return x > 0; });
    const bool any_wall = std::any_of(wall.begin(), wall.end(), [](double x) { return x > 0; });
    if (!any_cpu && any_wall) {
        s->median_cpu_seconds = s->p95_cpu_seconds = std::nan("");
        return;
    }
    s->median_cpu_seconds = SampleMedian(cpu);
    s->p95_cpu_seconds = SampleQuantile(cpu, 0.95);
}

/// Rows of one (method, params) set, sorted by pair.
MethodSummary SummarizeOne(std::vector<const ResultRow*> group, const ReportOptions& o,
                           const std::string& data_key, std::vector<std::string>* notes) {
    std::stable_sort(group.begin(), group.end(),
                     [](const ResultRow* a, const ResultRow* b) { return a->pair < b->pair; });
    MethodSummary s;
    s.method = group.front()->method;
    s.label = s.method;
    s.params = group.front()->params;
    s.pairs = group.size();
    std::vector<PairMetrics> finite;     // the rows whose metrics are numbers
    std::vector<PairMetrics> successes;  // those the success rule accepts
    std::vector<double> secs, cpu;
    // Per row (in pair order): hit or miss of each rate, and the scene the rate groups by.
    std::vector<bool> recalled, succeeded, recalled_3dm;
    std::vector<std::string> groups;
    const SuccessRule rule = SuccessRuleOf(o);
    for (const ResultRow* r : group) {
        groups.push_back(RateGroup(*r, o.rates_per));
        recalled.push_back(false);
        succeeded.push_back(false);
        recalled_3dm.push_back(false);
        cpu.push_back(r->result.cpu_seconds);
        if (r->status != Status::kOk && s.first_failure.empty()) {
            s.first_failure = fmt::format(
                "pair {}: {}: {}", r->pair, ToString(r->status),
                r->result.message.empty() ? std::string("(no message)") : r->result.message);
        }
        const PairMetrics m = MetricsIn(*r, o);
        secs.push_back(r->result.seconds);
        s.threads = r->threads;
        if (!AllFinite(m)) {
            // Not a number to average: the row counts as a failure and is named.
            ++s.failed;
            if (notes) {
                notes->push_back(
                    fmt::format("{}: {} pair {}: metrics not finite (null), counted "
                                "as failed",
                                Where(*r), r->method, r->pair));
            }
            continue;
        }
        if (r->status != Status::kOk) ++s.failed;
        finite.push_back(m);
        recalled.back() = m.mae_r < o.recall_r_deg && m.mae_t < o.recall_t;
        if (!std::isinf(rule.overlap_rmse) && !std::isfinite(m.overlap_rmse)) {
            throw std::runtime_error(
                Where(*r) + ": row has no metrics.overlap_rmse (written before it existed); "
                            "rescore it with `regbench score` for the success rule " + rule.name);
        }
        succeeded.back() = rule.Passes(m);
        if (succeeded.back()) successes.push_back(m);
        if (o.recall_3dmatch) {
            if (!std::isfinite(m.overlap_rmse)) {
                throw std::runtime_error(
                    Where(*r) +
                    ": row has no metrics.overlap_rmse (written before it existed); "
                    "rescore it with `regbench score` for the 3DMatch-style recall");
            }
            recalled_3dm.back() = m.overlap_rmse < kRecall3dmatchRmse * o.distance_scale &&
                                  m.rre < kRecall3dmatchRreDeg &&
                                  m.rte < kRecall3dmatchRte * o.distance_scale;
        }
    }
    // The stream names the pair file and the metric, not the method: every method on the same
    // pairs draws the same resamples (a paired bootstrap), so two methods with equal values
    // get equal CIs. The values are in pair order, so a CI does not depend on row order.
    const std::string id = data_key + "\n";
    const auto column = [&](const char* name, const std::vector<PairMetrics>& of) {
        const auto field = FindMetric(name).field;
        std::vector<double> v;
        v.reserve(of.size());
        for (const PairMetrics& m : of) v.push_back(m.*field);
        return v;
    };
    const auto boot = [&](const char* name) {
        return BootstrapMean(column(name, finite), o.bootstrap_samples, kDefaultBootstrapSeed,
                             StreamId(id + name));
    };
    s.mae_r = boot("mae_r");
    s.mae_t = boot("mae_t");
    s.ccd = boot("ccd");
    s.successful = successes.size();
    if (o.rre_rte_over == ErrorPairs::kAll) {
        s.rre = boot("rre");
        s.rte = boot("rte");
    } else {
        for (auto [e, name] : {std::pair{&s.rre, "rre"}, std::pair{&s.rte, "rte"}}) {
            *e = BootstrapMean(column(name, successes), o.bootstrap_samples,
                               kDefaultBootstrapSeed, StreamId(id + name + "/successful"));
        }
    }
    s.chamfer = boot("chamfer");
    // sqrt is increasing, so the root of the mean square's percentile interval is the root
    // mean square's.
    for (auto [rmse, mse] : {std::pair{&s.rmse_r, "mse_r"}, std::pair{&s.rmse_t, "mse_t"}}) {
        const Estimate e = boot(mse);
        *rmse = {std::sqrt(e.mean), std::sqrt(e.lo), std::sqrt(e.hi)};
    }
    const auto rate = [&](const std::vector<bool>& hits, const char* name) {
        return Rate(hits, groups, o.rates_per, o.bootstrap_samples,
                    StreamId(id + name + "/per-" + ToString(o.rates_per)), &s.rate_groups);
    };
    s.recall = rate(recalled, "recall");
    s.success = rate(succeeded, "success");
    s.recall_3dmatch = rate(recalled_3dm, "recall_3dmatch");
    s.median_seconds = SampleMedian(secs);
    s.p95_seconds = SampleQuantile(secs, 0.95);
    SummarizeCpuTime(secs, cpu, &s);
    s.mean_seconds =
        BootstrapMean(secs, o.bootstrap_samples, kDefaultBootstrapSeed, StreamId(id + "seconds"));
    SummarizeMetricOptions(group, finite, &s);
    return s;
}

/// Splits one table's rows by (method, params); refuses a (pair, method, params) seen twice.
std::vector<MethodSummary> SummarizeGroup(const std::vector<const ResultRow*>& rows,
                                          const ReportOptions& o, const std::string& data_key,
                                          std::vector<std::string>* notes) {
    std::vector<std::string> order;
    std::map<std::string, std::vector<const ResultRow*>> by_set;
    std::map<std::string, const ResultRow*> seen;  // (pair, method, params) -> first row
    std::map<std::string, int> sets_per_method;
    for (const ResultRow* r : rows) {
        const std::string set_key = r->method + "\n" + r->params.dump();
        const std::string row_key = std::to_string(r->pair) + "\n" + set_key;
        const auto [it, fresh] = seen.emplace(row_key, r);
        if (!fresh) {
            throw std::runtime_error(fmt::format(
                "{}: duplicate row for pair {}, method {} with the same params (first at {}); "
                "remove one (e.g. a shard given twice)",
                Where(*r), r->pair, r->method, Where(*it->second)));
        }
        if (!by_set.count(set_key)) {
            order.push_back(set_key);
            ++sets_per_method[r->method];
        }
        by_set[set_key].push_back(r);
    }
    std::vector<MethodSummary> out;
    for (const auto& key : order) {
        MethodSummary s = SummarizeOne(by_set[key], o, data_key, notes);
        // Several parameter sets of one method are separate rows, labelled by their params.
        if (sets_per_method[s.method] > 1) s.label = s.method + " " + s.params.dump();
        // A learned method's row names the checkpoint it ran: model and training step.
        const nlohmann::json& extra = by_set[key].front()->result.extra;
        if (extra.is_object() && extra.contains("checkpoint_label") &&
            extra["checkpoint_label"].is_string()) {
            s.label += " (" + extra["checkpoint_label"].get<std::string>() + ")";
        }
        out.push_back(std::move(s));
    }
    return out;
}

}  // namespace

/// The pairs each (method, params) of a table has; refuses different sets naming them, or
/// (common) drops the rows outside their intersection and says what was dropped.
static std::string RestrictToCommonPairs(std::vector<const ResultRow*>* group, bool common) {
    std::vector<std::string> order;
    std::map<std::string, std::set<std::size_t>> pairs;
    for (const ResultRow* r : *group) {
        const std::string label = r->method + " " + r->params.dump();
        if (!pairs.count(label)) order.push_back(label);
        pairs[label].insert(r->pair);
    }
    std::set<std::size_t> shared = pairs[order.front()];
    bool differ = false;
    for (const auto& label : order) {
        differ |= pairs[label] != shared;
        std::set<std::size_t> both;
        for (const std::size_t k : pairs[label]) {
            if (shared.count(k)) both.insert(k);
        }
        shared = std::move(both);
    }
    if (!differ) return "";
    const auto name = [](const std::string& label) { return label.substr(0, label.find(' ')); };
    std::string counts;
    for (const auto& label : order) {
        counts +=
            fmt::format("{}{}: {}", counts.empty() ? "" : ", ", name(label), pairs[label].size());
        if (common && pairs[label].size() != shared.size()) {
            counts += fmt::format(" -> {}", shared.size());
        }
    }
    if (!common) {
        throw std::runtime_error(fmt::format(
            "methods of one table were measured on different pairs of {} ({} pairs); "
            "a table would compare them on different data. Run them on the same pairs, or pass "
            "--common-pairs to compare them on the {} pairs they share",
            group->front()->data.pairs_file, counts, shared.size()));
    }
    if (shared.empty()) {
        throw std::runtime_error(
            fmt::format("methods of one table share no pair of {} ({} pairs): nothing to compare",
                        group->front()->data.pairs_file, counts));
    }
    group->erase(std::remove_if(group->begin(), group->end(),
                                [&](const ResultRow* r) { return !shared.count(r->pair); }),
                 group->end());
    return fmt::format("restricted to the {} pairs every method has (--common-pairs; {} pairs)",
                       shared.size(), counts);
}

ReportOptions ForData(const ReportOptions& o, const DataTag& data) {
    ReportOptions out = o;
    const double factor = data.scale / o.distance_scale;  // from o's scale to the data's
    if (!o.recall_t_given) out.recall_t *= factor;
    if (!o.success_rte_given) out.success_rte *= factor;
    out.distance_scale = data.scale;
    return out;
}

SuccessRule SuccessRuleOf(const ReportOptions& o) {
    return FindSuccessRule(o.success_rule, o.success_rre_deg, o.success_rte, o.distance_scale);
}

std::vector<ReportTable> BuildTables(const std::vector<ResultRow>& rows,
                                     const ReportOptions& o) {
    std::vector<std::string> order;
    std::map<std::string, std::vector<const ResultRow*>> groups;
    for (const auto& r : rows) {
        const EulerConvention euler = o.euler.value_or(r.euler);
        const std::string key = DataKey(r.data) + "\neuler:" + ToString(euler);
        if (!groups.count(key)) order.push_back(key);
        groups[key].push_back(&r);
    }
    std::vector<ReportTable> tables;
    for (const auto& key : order) {
        auto& group = groups[key];
        ReportTable t;
        t.subset = RestrictToCommonPairs(&group, o.common_pairs);
        t.data = group.front()->data;
        t.euler = o.euler.value_or(group.front()->euler);
        std::set<std::string> files;
        for (const ResultRow* r : group) {
            const std::string file = r->origin.substr(0, r->origin.rfind(':'));
            if (!file.empty() && files.insert(file).second) t.files.push_back(file);
        }
        t.methods = SummarizeGroup(group, ForData(o, t.data), DataKey(t.data), &t.notes);
        t.rows = group;
        t.environment = DescribeEnvironment(group);
        tables.push_back(std::move(t));
    }
    return tables;
}

std::vector<MethodSummary> Summarize(const std::vector<ResultRow>& rows, const ReportOptions& o) {
    std::vector<const ResultRow*> ptrs;
    for (const auto& r : rows) ptrs.push_back(&r);
    if (rows.empty()) return SummarizeGroup(ptrs, o, "", nullptr);
    return SummarizeGroup(ptrs, ForData(o, rows.front().data), DataKey(rows.front().data),
                          nullptr);
}

std::string DescribeTable(const ReportTable& t) {
    const DataTag& d = t.data;
    std::string out = fmt::format("dataset `{}`", d.dataset);
    if (!d.dataset_sha256.empty()) out += fmt::format(" (sha256 {})", d.dataset_sha256);
    out += fmt::format(", protocol `{}`, pairing `{}`, seed {}, file `{}`", d.protocol, d.pairing,
                       d.seed.dump(), d.pairs_file);
    if (!d.content_hash.empty()) out += fmt::format(" (content {})", d.content_hash);
    out += fmt::format("; mae_r/rmse_r: scipy as_euler('{}')", ToString(t.euler));
    if (t.euler == EulerConvention::kZyx) out += ", the paper's convention";
    if (t.euler == EulerConvention::kXyz) out += ", RPMNet's convention";
    if (!t.subset.empty()) out += "; " + t.subset;
    return out;
}

namespace {

Cell Mean(const Estimate& e, std::size_t pairs) {
    Cell c = MeasuredCell(e.mean, pairs);
    c.ci_lo = e.lo;
    c.ci_hi = e.hi;
    return c;
}

Column Col(const std::string& key, const std::string& header, int decimals,
           CiStyle ci = CiStyle::kHidden) {
    return {key, header, CellSource::kMeasured, Better::kNone, decimals, ci};
}

/// A column of a mean over pairs of the metric `name` (rmse_r: of mse_r), in its format, shown
/// as mean ± the half-width of its CI; `compact` false: in the full table only.
Column MetricCol(const std::string& key, const std::string& name, const std::string& header,
                 bool compact = true) {
    Column c = Col(key, header, FindMetric(name).decimals, CiStyle::kPlusMinus);
    c.compact = compact;
    return c;
}

/// A rate's column: the rate and its Wilson interval.
Column RateCol(const std::string& key, const std::string& header) {
    return Col(key, header, kFractionDecimals, CiStyle::kValueInterval);
}

/// The largest inlier threshold the rows used (0: Open3D's fitness pair was not measured).
double InlierThreshold(const ReportTable& rt) {
    double threshold = 0.0;
    for (const auto& s : rt.methods) threshold = std::max(threshold, s.inlier_threshold);
    return threshold;
}

/// The summary table's columns (Open3D's fitness pair at `threshold` when it is > 0).
std::vector<Column> SummaryColumns(const ReportTable& rt, const ReportOptions& o,
                                   double threshold) {
    // Every number with its 95% CI: means by bootstrap, rates by Wilson (docs/reports.md).
    const std::string over = o.rre_rte_over == ErrorPairs::kAll ? "" : " (successful)";
    std::vector<Column> columns = {
        Col("pairs", "pairs", 0), Col("failed", "failed", 0),
        MetricCol("mae_r", "mae_r", "mae_r [deg]"),
        // The interval's bounds at 3 decimals, as the documented table has always shown them.
        Col("mae_r.ci95", "mae_r 95% CI", 3, CiStyle::kInterval),
        MetricCol("mae_t", "mae_t", "mae_t"), MetricCol("ccd", "ccd", "ccd"),
        MetricCol("rre", "rre", "rre [deg]" + over, false), MetricCol("rte", "rte", "rte" + over, false),
        MetricCol("rmse_r", "mse_r", "rmse_r", false),
        MetricCol("rmse_t", "mse_t", "rmse_t", false),
        RateCol("recall", fmt::format("recall@({:g},{:g})", o.recall_r_deg, o.recall_t)),
        RateCol("success",
                SuccessRuleOf(o).Header())};
    if (o.recall_3dmatch) columns.push_back(RateCol("recall_3dmatch", "3DMatch recall"));
    // A clip other than the paper's is in the header; Open3D's pair only when measured.
    const double clip = rt.methods.empty() ? kCcdClip : rt.methods.front().ccd_clip;
    for (const auto& s : rt.methods) {
        if (s.ccd_clip != clip) {
            throw std::runtime_error(fmt::format(
                "{}: ccd measured with clip {:g} for {} and {:g} for {}: not comparable; run "
                "them with one --ccd-clip",
                rt.data.pairs_file, clip, rt.methods.front().label, s.ccd_clip, s.label));
        }
    }
    for (Column& c : columns) {
        if (c.key == "ccd" && clip != kCcdClip) c.header = fmt::format("ccd (clip {:g})", clip);
    }
    if (threshold > 0.0) {
        columns.push_back(
            Col("fitness", fmt::format("fitness@{:g}", threshold), kFractionDecimals));
        columns.push_back(Col("inlier_rmse", fmt::format("inlier rmse@{:g}", threshold), 4));
    }
    columns.push_back(Col("median_seconds", "median s", kSecondsDecimals));
    columns.push_back(Col("mean_seconds", "mean s", kSecondsDecimals, CiStyle::kPlusMinus));
    columns.back().compact = false;
    // Data columns, in CSV and JSON only (the interval column: mae_r shows its CI itself).
    columns[3].shown = false;
    columns.push_back(MetricCol("chamfer", "chamfer", "chamfer"));
    columns.push_back(Col("threads", "threads", 0));
    columns.push_back(Col("params", "params", 0));
    for (std::size_t c = columns.size() - 3; c < columns.size(); ++c)
        columns[c].shown = false;
    return columns;
}

/// The pairs behind a row's rre / rte means: all of them, or the successful ones.
std::size_t ErrorPairsCount(const MethodSummary& s, const ReportOptions& o) {
    return o.rre_rte_over == ErrorPairs::kAll ? s.pairs : s.successful;
}

/// Why rows failed: the first message per method, and the rows counted as failed.
void AddFailureNotes(const ReportTable& rt, Table& t) {
    std::string why;  // the first message per method whose calls failed
    for (const MethodSummary& m : rt.methods) {
        if (!m.first_failure.empty()) {
            why += fmt::format("\n- {}: {} of {} failed; first: {}", m.label, m.failed, m.pairs,
                               OneLineMessage(m.first_failure));
        }
    }
    if (!why.empty()) t.notes.push_back("Why calls failed (first message per method):" + why);
    if (!rt.notes.empty()) {
        std::string failed = "Rows counted as failed:";
        for (const auto& n : rt.notes) failed += "\n- " + n;
        t.notes.push_back(failed);
    }
}

/// The thresholds of the table in the data's own length unit, and a sentence for each metric
/// that saturated for every method (issue 54 item 1): CCD at its ceiling 2 * clip, a rate at 0.
std::string ThresholdsCaption(const ReportTable& rt, const ReportOptions& o) {
    const double clip = rt.methods.empty() ? kCcdClip : rt.methods.front().ccd_clip;
    std::string caption = fmt::format(
        "; thresholds in the data's length unit: recall mae_r < {:g} deg and mae_t < {:g}; "
        "success rre < {:g} deg and rte < {:g}; CCD clip {:g} (the paper's translation "
        "thresholds and clip are 0.1, for unit-sphere objects).",
        o.recall_r_deg, o.recall_t, o.success_rre_deg, o.success_rte, clip);
    if (o.distance_scale != 1.0) {
        std::vector<std::string> given;
        if (o.recall_t_given) given.push_back("--recall-t");
        if (o.success_rte_given) given.push_back("--success-rte");
        caption += fmt::format(
            " The pair file's scale is {0:g} (`generate --scale`): every distance threshold not "
            "given on the command line is its unit-sphere default times {0:g}{1}.",
            o.distance_scale,
            given.empty() ? "" : fmt::format(" (given as is: {})", fmt::join(given, ", ")));
    }
    if (rt.methods.empty()) return caption;
    const auto every = [&rt](auto&& pred) {
        return std::all_of(rt.methods.begin(), rt.methods.end(), pred);
    };
    if (every([clip](const MethodSummary& m) { return m.ccd.mean >= 0.999 * 2.0 * clip; })) {
        caption += fmt::format(
            " Saturated: CCD is at its ceiling 2 x clip = {:g} for every method, so it ranks "
            "nothing here; give `run --ccd-clip` in the data's units (about 10% of the clouds' "
            "radius).",
            2.0 * clip);
    }
    const auto zero = [&every](Estimate MethodSummary::*rate) {
        return every([rate](const MethodSummary& m) { return (m.*rate).mean == 0.0; });
    };
    if (zero(&MethodSummary::recall) || zero(&MethodSummary::success)) {
        caption += fmt::format(
            " Saturated: {} 0 for every method; the thresholds may not fit the data's units "
            "(`report --recall-t`, `--success-rte`).",
            zero(&MethodSummary::recall) && zero(&MethodSummary::success) ? "recall and success are"
            : zero(&MethodSummary::recall)                                ? "recall is"
                                                                          : "success is");
    }
    return caption;
}

}  // namespace

Table SummaryTable(const ReportTable& rt, const ReportOptions& given) {
    const ReportOptions o = ForData(given, rt.data);  // thresholds in the data's units
    Table t;
    t.id = rt.data.pairs_file + ":" + ToString(rt.euler);
    t.caption = "Data: " + DescribeTable(rt) + ThresholdsCaption(rt, o);
    t.caption += "\n" + DescribeConventions(rt, o);
    const double threshold = InlierThreshold(rt);
    t.columns = SummaryColumns(rt, o, threshold);
    for (const auto& s : rt.methods) {
        const std::size_t n = s.pairs;
        RowCells cells = {{"pairs", MeasuredCell(static_cast<double>(n), n)},
                          {"failed", MeasuredCell(static_cast<double>(s.failed), n)},
                          {"mae_r", Mean(s.mae_r, n)},
                          {"mae_r.ci95", Mean(s.mae_r, n)},
                          {"mae_t", Mean(s.mae_t, n)},
                          {"ccd", Mean(s.ccd, n)},
                          {"rre", Mean(s.rre, ErrorPairsCount(s, o))},
                          {"rte", Mean(s.rte, ErrorPairsCount(s, o))},
                          {"rmse_r", Mean(s.rmse_r, n)},
                          {"rmse_t", Mean(s.rmse_t, n)},
                          {"recall", Mean(s.recall, n)},
                          {"success", Mean(s.success, n)},
                          {"median_seconds", MeasuredCell(s.median_seconds, n)},
                          {"mean_seconds", Mean(s.mean_seconds, n)},
                          {"chamfer", Mean(s.chamfer, n)},
                          {"threads", MeasuredCell(double(s.threads), n)}};
        if (o.recall_3dmatch) cells.emplace_back("recall_3dmatch", Mean(s.recall_3dmatch, n));
        if (threshold > 0.0) {
            cells.emplace_back("fitness", MeasuredCell(s.fitness, n));
            cells.emplace_back("inlier_rmse", MeasuredCell(s.inlier_rmse, n));
        }
        Cell params;
        params.source = CellSource::kLabel;
        params.text = s.params.dump();
        cells.emplace_back("params", params);
        t.AddRow(s.label, cells);
    }
    Provenance p;
    p.pairs_file = rt.data.pairs_file;
    p.pairs_hash = rt.data.content_hash;
    p.dataset = rt.data.dataset;
    p.protocol = rt.data.protocol;
    p.pairing = rt.data.pairing;
    p.seed = rt.data.seed;
    t.provenance = {p};
    AddFailureNotes(rt, t);
    return t;
}

std::vector<Table> SummaryTables(const std::vector<ReportTable>& tables, const ReportOptions& o) {
    std::vector<Table> out;
    for (std::size_t i = 0; i < tables.size(); ++i) {
        out.push_back(SummaryTable(tables[i], o));
        if (tables.size() > 1) {
            out.back().caption =
                fmt::format("Table {} of {}. ", i + 1, tables.size()) + out.back().caption;
        }
    }
    return out;
}

}  // namespace regbench
