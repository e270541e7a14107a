#include "reports/paper_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>

#include "reports/paper_tables.hpp"
#include "reports/row_access.hpp"
#include "reports/statistics.hpp"
#include "reports/timing.hpp"

namespace regbench {
namespace {

const std::vector<std::string> kMetrics = {"mae_r", "mae_t", "ccd"};

std::string MetricHeader(const std::string& m) {
    if (m == "mae_r") return "MAE(R)";
    if (m == "mae_t") return "MAE(t)";
    if (m == "ccd") return "CCD";
    return m;
}

/// The paper's row name of a result row: the set's label, else the paper's method name.
std::string PaperRowOf(const ResultRow& row, const ResultSet& set, const PaperRows& paper_rows) {
    if (!set.row_label.empty()) return set.row_label;
    return PaperRowName(paper_rows, row.method).value_or(row.method);
}

/// "ours / full" or the set's group: how the caption names a set.
std::string SetName(const ResultSet& s) {
    return (s.group.empty() ? "ours" : s.group) + (s.row_label.empty() ? "" : " / " + s.row_label);
}

/// "dataset `cgal` (split test, protocol partial, pairing independent, 100 pairs, seed 1)".
std::string DescribeSetData(const ResultSet& s) {
    const Provenance& p = s.provenance;
    std::set<std::size_t> pairs;
    for (const auto& r : s.rows) pairs.insert(r.pair);
    std::string d = fmt::format(
        "dataset `{}` (split {}, protocol {}, pairing {}, {} pairs, seed {}, file {})", p.dataset,
        p.split.empty() ? "-" : p.split, p.protocol, p.pairing.empty() ? "-" : p.pairing,
        pairs.size(), p.seed.is_null() ? std::string("-") : p.seed.dump(), p.pairs_file);
    if (!p.selection.empty()) d += ", " + p.selection + " selection";
    if (std::isfinite(p.noise_sigma)) {
        d += p.noise_sigma == 0.0 ? ", noise-free"
                                  : fmt::format(", noise sigma {:g}", p.noise_sigma);
    }
    if (!p.fallback.empty()) d += " [" + p.fallback + "]";
    if (!p.weights.empty()) d += "; weights: " + p.weights;
    return d;
}

/// The ground-truth CCD floor of every set's pairs under the table (the CCD the true transform
/// itself scores: what a perfect registration gets; a method can only go below it by fitting
/// the noise), or why there is none.
void AddFloorNotes(const std::vector<ResultSet>& sets, Table* t) {
    // Sets with the same floor (an ablation's variants, the cluster-count columns: the same
    // pairs) share one note naming their groups.
    struct Floor {
        double value;
        std::vector<std::string> groups;
    };
    std::vector<Floor> floors;
    for (const auto& s : sets) {
        const double value = s.provenance.gt_ccd_floor;
        if (!std::isfinite(value)) continue;
        auto f = std::find_if(floors.begin(), floors.end(),
                              [&](const Floor& x) { return x.value == value; });
        if (f == floors.end()) f = floors.insert(floors.end(), Floor{value, {}});
        if (!s.group.empty() &&
            std::find(f->groups.begin(), f->groups.end(), s.group) == f->groups.end()) {
            f->groups.push_back(s.group);
        }
    }
    for (const auto& f : floors) {
        t->notes.push_back(fmt::format(
            "Ground-truth CCD floor{}: {:.4f} (CCD of the true transform on these pairs: what a "
            "perfect registration scores)",
            f.groups.empty() ? "" : fmt::format(" ({})", fmt::join(f.groups, ", ")), f.value));
    }
    if (floors.empty()) {
        t->notes.push_back(
            "Ground-truth CCD floor: not known (no pair file behind this table's rows).");
    }
}

/// Per group and metric a measured column and (for a table the paper has) the paper's.
void AddColumns(const PaperTableSpec& spec, bool published, Table* t) {
    for (const auto& g : spec.groups) {
        if (!g.empty()) t->column_groups.push_back(g);
        for (const auto& m : spec.metrics) {
            const std::string key = g.empty() ? m : g + "." + m;
            const std::string head = g.empty() ? MetricHeader(m) : MetricHeader(m) + " " + g;
            const int d = FindMetric(m).decimals;
            t->columns.push_back({key, head, CellSource::kMeasured, Better::kLower, d});
            if (!published) continue;
            // A regbench-only group's paper column names the paper group it shows.
            const std::string pg = PaperGroupOf(spec, g);
            const std::string paper_head =
                pg.empty() ? MetricHeader(m) : MetricHeader(m) + " " + pg;
            t->columns.push_back(
                {"paper:" + key, "paper " + paper_head, CellSource::kPaper, Better::kNone, d});
        }
    }
}

/// The caption (its first sentence, then each side's data), provenance and floor notes of a
/// paper table; a table the paper lacks (`published` false) has no paper side.
void DescribeSides(const PaperTableSpec& spec, const nlohmann::json& pt, bool published,
                   const std::vector<ResultSet>& sets, Table* t) {
    // Sets on the same data (an ablation's variants) are described once, naming them all.
    struct Described {
        std::string group, names, data;
    };
    std::vector<Described> described;  // in set order
    for (const auto& s : sets) {
        const std::string data = DescribeSetData(s);
        const auto same = std::find_if(described.begin(), described.end(),
                                       [&](const Described& d) { return d.data == data; });
        if (same == described.end()) {
            described.push_back({s.group, SetName(s), data});
        } else {  // "ours / full, no_SPE": a row label alone within its group
            same->names +=
                ", " + (s.group == same->group && !s.row_label.empty() ? s.row_label : SetName(s));
        }
        t->provenance.push_back(s.provenance);
        t->provenance.back().group = s.group;
    }
    std::string ours;
    for (const auto& d : described) ours += (ours.empty() ? "" : "; ") + d.names + ": " + d.data;
    AddFloorNotes(sets, t);
    const std::string paper_side =
        published
            ? fmt::format(" Paper: {} as published (their pairs, their machine).", spec.paper_data)
            : "";
    t->caption = fmt::format(
        "{}. Ours: {}.{} Measured cells are mean ± 95% bootstrap half-width; '-' = not run{}.",
        spec.caption.empty() ? pt.value("caption", std::string()) : spec.caption,
        ours.empty() ? "no result rows" : ours, paper_side,
        published ? " or not in the paper" : "");
    std::vector<const ResultRow*> rows;
    for (const auto& s : sets) {
        for (const ResultRow& r : s.rows) rows.push_back(&r);
    }
    t->caption += "\n" + PaperTableConventions(rows);
}

}  // namespace

const std::vector<PaperTableSpec>& PaperTableSpecs() {
    static const std::vector<PaperTableSpec> kSpecs = {
        {"table1_modelnet_partial",
         "Tab. 1: partial-to-partial registration",
         {"same_category", "cross_category"},
         kMetrics,
         true,
         "ModelNet40"},
        {"table2_modelnet_noise_density",
         "Tab. 2: jitter noise and density variation",
         {"jitter", "density"},
         kMetrics,
         true,
         "ModelNet40"},
        {"table3_indoor",
         "Tab. 3: indoor scenes",
         {"7scenes", "icl_nuim"},
         kMetrics,
         true,
         "7Scenes and ICL-NUIM"},
        {"table4_ablation_components",
         "Tab. 4: OGMM component ablation",
         {""},
         kMetrics,
         false,
         "ModelNet40 same-category partial"},
        {"table5_ablation_losses",
         "Tab. 5: OGMM loss ablation",
         {""},
         kMetrics,
         false,
         "ModelNet40 same-category partial"},
        {"supp_overlap_ratio",
         "Supp.: overlap ratio",
         {"30%", "40%", "50%", "60%", "70%"},
         kMetrics,
         true,
         "noisy ModelNet40"},
        {"supp_cluster_count",
         "Supp.: number of GMM components",
         {"8", "16", "32", "48", "64"},
         kMetrics,
         true,
         "noisy ModelNet40, 50% overlap"},
        {"supp_complete",
         "Supp.: complete-to-complete and complete-to-partial",
         // c2c_clean: the same complete clouds noise-free from one shared sample, offered
         // because the paper's CPD CCD (0.0037) is below what noisy independent samples allow.
         {"c2c", "c2p", "c2c_clean"},
         kMetrics,
         true,
         "noisy ModelNet40",
         {{"c2c_clean", "c2c"}}},
    };
    return kSpecs;
}

const PaperTableSpec& FindPaperTableSpec(const std::string& id) {
    std::string known;
    for (const auto& s : PaperTableSpecs()) {
        if (s.id == id) return s;
        known += (known.empty() ? "" : ", ") + s.id;
    }
    throw std::invalid_argument("unknown paper table '" + id + "' (known: " + known +
                                ", table6_inference_time)");
}

std::string PaperGroupOf(const PaperTableSpec& spec, const std::string& g) {
    const auto it = spec.paper_group_of.find(g);
    return it == spec.paper_group_of.end() ? g : it->second;
}

double PaperCell(const nlohmann::json& paper, const std::string& table,
                 const std::string& paper_row, const std::string& group,
                 const std::string& metric) {
    const auto& tables = paper.at("tables");
    if (!tables.contains(table)) return std::nan("");
    const auto& t = tables.at(table);
    const auto& columns = t.at("columns");
    const auto& rows = t.at("rows");
    const auto column = [&](const std::string& name) -> int {
        for (std::size_t i = 0; i < columns.size(); ++i) {
            if (columns[i].get<std::string>() == name) return static_cast<int>(i);
        }
        return -1;
    };
    // Sweep tables list metrics as rows and groups as columns, for one method (the table's
    // "method" in the paper's file).
    if (rows.contains(metric) && !group.empty() && column(group) >= 0) {
        if (paper_row != t.value("method", "")) return std::nan("");
        return rows.at(metric).at(static_cast<std::size_t>(column(group))).get<double>();
    }
    const int c = column(group.empty() ? metric : group + "." + metric);
    if (c < 0 || !rows.contains(paper_row)) return std::nan("");
    return rows.at(paper_row).at(static_cast<std::size_t>(c)).get<double>();
}

namespace {

/// The measured cell of row `label`, metric `m`: the mean over the set's rows of that row,
/// with its bootstrap CI and pair count.
Cell MeasuredCell(const ResultSet& set, const std::string& label, const std::string& m,
                  const PaperTableOptions& o) {
    Cell measured;
    const MetricField& metric = FindMetric(m);
    std::vector<double> v;
    std::size_t n = 0;
    for (const auto& r : set.rows) {
        if (PaperRowOf(r, set, o.paper_rows) != label) continue;
        ++n;
        // Null metrics are failures: they keep the pair count honest but no
        // number can stand in for them, so the cell says how many.
        if (const auto x = metric.Of(r.metrics)) v.push_back(*x);
    }
    // The stream of the breakdowns (reports/breakdown.cpp), named by the metric alone: one CI
    // per mean, and every method on the same pairs draws the same resamples (paired).
    const BootstrapCi ci = BootstrapMean(v, o.bootstrap_samples, o.seed, StreamId(m));
    measured.value = ci.mean;
    if (v.size() >= 2) {
        measured.ci_lo = ci.lo;
        measured.ci_hi = ci.hi;
    }
    measured.pairs = n;
    if (v.size() < n) {
        measured.text = fmt::format("{:.{}f} ({} null)", ci.mean, metric.decimals, n - v.size());
    }
    return measured;
}

}  // namespace

Table BuildPaperTable(const PaperTableSpec& spec, const std::vector<ResultSet>& sets,
                      const nlohmann::json& paper, const PaperTableOptions& o) {
    Table t;
    t.id = spec.id;
    t.title = spec.title;
    t.row_header = spec.rows_are_methods ? "method" : "variant";
    // Row order: the paper's (for sweep tables: the table's one method), then measured rows the
    // paper lacks.
    std::vector<std::string> order;
    const auto& pt = paper.at("tables").value(spec.id, nlohmann::json::object());
    const bool published = paper.at("tables").contains(spec.id);
    const bool sweep = pt.contains("rows") && pt["rows"].contains("mae_r");
    if (sweep) {
        order.push_back(pt.value("method", ""));
    } else if (pt.contains("row_order")) {  // recorded by LoadPaperTables in the paper's order
        order = pt["row_order"].get<std::vector<std::string>>();
    } else if (pt.contains("rows")) {
        for (const auto& r : pt["rows"].items()) order.push_back(r.key());
    }
    for (const auto& s : sets) {
        for (const auto& r : s.rows) {
            const std::string label = PaperRowOf(r, s, o.paper_rows);
            if (std::find(order.begin(), order.end(), label) == order.end()) order.push_back(label);
        }
    }
    AddColumns(spec, published, &t);
    // Reasons for rows that could not be measured, keyed by paper row name.
    std::map<std::string, std::string> reasons;
    for (const auto& [method, why] : o.unavailable)
        reasons[PaperRowName(o.paper_rows, method).value_or(method)] = why;
    for (const auto& label : order) {
        RowCells cells;
        for (const auto& g : spec.groups) {
            const ResultSet* set = nullptr;
            for (const auto& s : sets) {
                if (s.group != g) continue;
                for (const auto& r : s.rows) {
                    if (PaperRowOf(r, s, o.paper_rows) == label) set = &s;
                }
            }
            for (const auto& m : spec.metrics) {
                Cell measured;
                if (set != nullptr) {
                    measured = MeasuredCell(*set, label, m, o);
                } else if (reasons.count(label)) {
                    measured.text = reasons[label];
                }
                const std::string key = g.empty() ? m : g + "." + m;
                cells.emplace_back(key, measured);
                if (!published) continue;
                Cell p;
                p.source = CellSource::kPaper;
                p.value = PaperCell(paper, spec.id, label, PaperGroupOf(spec, g), m);
                cells.emplace_back("paper:" + key, p);
            }
        }
        t.AddRow(label, cells);
    }
    DescribeSides(spec, pt, published, sets, &t);
    return t;
}

namespace {

/// One row of Tab. 6: a method's (or a labelled set's) CPU times and, for a learned method,
/// its network's CPU time, MACs and floor (the row keys the learned methods write, extra.*).
struct TimingRow {
    std::vector<double> cpu, network, gmac, floor;
    int threads = 1;
    /// Points per cloud of the timed calls, source and target alike (the rows'
    /// source_points / target_points); empty when the rows predate them.
    std::vector<std::size_t> points;
    std::string blas;
};

/// Tab. 6's `points` cell: the point count every timed call had, or "lo-hi" where they
/// differ; blank for rows that do not record it (not the pair file's sampled count, which a
/// crop reduces: 1024 sampled, 717 kept).
Cell PointsCell(const std::vector<std::size_t>& points) {
    Cell c;
    if (points.empty()) return c;
    const auto [lo, hi] = std::minmax_element(points.begin(), points.end());
    c.value = static_cast<double>(*lo);
    if (*lo != *hi) c.text = fmt::format("{}-{}", *lo, *hi);
    return c;
}

double ExtraNumber(const ResultRow& row, const char* key) {
    if (!row.result.extra.is_object()) return std::nan("");
    const auto v = row.result.extra.find(key);
    return v != row.result.extra.end() && v->is_number() ? v->get<double>() : std::nan("");
}

/// Mean of `v`, NaN (a blank cell) when empty.
double MeanOrBlank(const std::vector<double>& v) {
    return v.empty() ? std::nan("") : SampleMean(v);
}

/// A mean of per-call times with its 95% bootstrap CI (stream: the row label and quantity).
void SetMeanWithCi(const std::vector<double>& v, const std::string& stream, Cell* c) {
    c->value = MeanOrBlank(v);
    if (v.size() < 2) return;
    const BootstrapCi ci = BootstrapMean(v, 1000, kDefaultBootstrapSeed, StreamId(stream));
    c->ci_lo = ci.lo;
    c->ci_hi = ci.hi;
}

/// The timing rows of Tab. 6: by method, or by the set's label (a variant such as
/// OGMM_full_attention), in order of first appearance; and the learned methods' BLAS notes.
struct Timings {
    std::vector<std::string> order;
    std::map<std::string, TimingRow> by_label;
    /// GEMM rates (GMAC/s) by BLAS: each process measures its own (runners/, learned.cpp), so
    /// the shards of one run (reproduce --shard) bring one each.
    std::map<std::string, std::vector<double>> learned_blas;
};

Timings CollectTimings(const std::vector<ResultSet>& sets) {
    Timings t;
    for (const auto& s : sets) {
        for (const auto& r : s.rows) {
            const std::string label = s.row_label.empty() ? r.method : s.row_label;
            if (!t.by_label.count(label)) t.order.push_back(label);
            TimingRow& row = t.by_label[label];
            row.threads = r.threads;
            if (r.status != Status::kOk) continue;
            for (const auto& n : {r.source_points, r.target_points}) {
                if (n) row.points.push_back(*n);
            }
            // Rows written before cpu_seconds existed read 0 s: no CPU time to show (as in
            // runners/timing_summary).
            if (r.result.cpu_seconds > 0.0) row.cpu.push_back(1e3 * r.result.cpu_seconds);
            const double network = ExtraNumber(r, "network_cpu_seconds");
            const double macs = ExtraNumber(r, "macs");
            const double floor = ExtraNumber(r, "floor_seconds");
            if (std::isfinite(network)) row.network.push_back(1e3 * network);
            if (std::isfinite(macs)) row.gmac.push_back(1e-9 * macs);
            if (std::isfinite(floor)) row.floor.push_back(1e3 * floor);
            const auto blas =
                r.result.extra.is_object() ? r.result.extra.find("blas") : r.result.extra.end();
            if (blas != r.result.extra.end() && blas->is_string() && std::isfinite(floor)) {
                t.learned_blas[blas->get<std::string>()].push_back(
                    ExtraNumber(r, "gemm_gmac_per_s"));
            }
        }
    }
    return t;
}

}  // namespace

Table BuildTimingTable(const std::vector<ResultSet>& sets, const nlohmann::json& paper,
                       const std::string& cpu_model, const std::string& blas,
                       const PaperRows& paper_rows) {
    Table t;
    t.id = "table6_inference_time";
    t.title = "Tab. 6: time per pair";
    t.columns = {{"cpu_ms_mean", "CPU ms", CellSource::kMeasured, Better::kLower, 1},
                 {"cpu_ms_median", "median CPU ms", CellSource::kMeasured, Better::kLower, 1},
                 {"network_ms", "network CPU ms", CellSource::kMeasured, Better::kLower, 1},
                 {"gmac", "GMAC", CellSource::kMeasured, Better::kNone, 2},
                 {"floor_ms", "floor ms", CellSource::kMeasured, Better::kNone, 1},
                 {"x_floor", "x floor", CellSource::kMeasured, Better::kNone, 2},
                 {"points", "points", CellSource::kMeasured, Better::kNone, 0},
                 {"threads", "threads", CellSource::kMeasured, Better::kNone, 0},
                 {"paper:ms", "paper ms", CellSource::kPaper, Better::kNone, 0}};
    const auto& rows = paper.at("tables").at("table6_inference_time").at("rows");
    const nlohmann::json of =
        paper.at("tables").at("table6_inference_time").value("row_of", nlohmann::json::object());
    Timings timings = CollectTimings(sets);
    for (const auto& label : timings.order) {
        const TimingRow& m = timings.by_label[label];
        Cell mean, median, network, gmac, floor, ratio, th, p;
        Cell points = PointsCell(m.points);
        SetMeanWithCi(m.cpu, label + "/cpu_ms", &mean);
        median.value = m.cpu.empty() ? std::nan("") : SampleMedian(m.cpu);
        mean.pairs = median.pairs = m.cpu.size();
        SetMeanWithCi(m.network, label + "/network_ms", &network);
        gmac.value = MeanOrBlank(m.gmac);
        floor.value = MeanOrBlank(m.floor);
        // CPU time of the network over the time its MACs take at the GEMM rate: the mean of
        // the network's CPU time over the mean floor (the same rows).
        if (!m.network.empty() && m.network.size() == m.floor.size())
            ratio.value = network.value / floor.value;
        network.pairs = gmac.pairs = floor.pairs = ratio.pairs = m.network.size();
        th.value = m.threads;
        p.source = CellSource::kPaper;
        const std::string name = PaperRowName(paper_rows, label).value_or(label);
        if (rows.contains(name)) {
            p.value = 1e3 * rows[name].at(0).get<double>();
        } else if (of.contains(name) && rows.contains(of[name].get<std::string>())) {
            // the paper's row a method's own fills (e.g. the clustered-attention time of a
            // clustered-attention checkpoint): the table's "row_of" in the paper's file
            p.value = 1e3 * rows[of[name].get<std::string>()].at(0).get<double>();
        }
        t.AddRow(label, {{"cpu_ms_mean", mean},
                         {"cpu_ms_median", median},
                         {"network_ms", network},
                         {"gmac", gmac},
                         {"floor_ms", floor},
                         {"x_floor", ratio},
                         {"points", points},
                         {"threads", th},
                         {"paper:ms", p}});
    }
    // One provenance and floor note per pair file (a variant runs on the pairs of the rows).
    std::vector<ResultSet> files;
    for (const auto& s : sets) {
        const bool seen = std::any_of(files.begin(), files.end(), [&](const ResultSet& f) {
            return f.provenance.pairs_file == s.provenance.pairs_file;
        });
        if (!seen) files.push_back({s.group, {}, s.provenance, ""});
    }
    for (const auto& s : files) t.provenance.push_back(s.provenance);
    AddFloorNotes(files, &t);
    std::string learned;
    for (const auto& [b, rates] : timings.learned_blas) {
        // One BLAS once, at its rate or, measured by several processes, their range.
        const auto [lo, hi] = std::minmax_element(rates.begin(), rates.end());
        const std::string low = fmt::format("{:.1f}", *lo);
        const std::string high = fmt::format("{:.1f}", *hi);
        learned +=
            fmt::format("{}{} at {} GMAC/s single-thread fp32 (LibTorch mm, 717x512x512)",
                        learned.empty() ? "" : "; ", b, low == high ? low : low + "-" + high);
    }
    t.caption = fmt::format(
        "CPU milliseconds of the method's own call per pair (successful calls; the harness's "
        "loading, metrics and I/O excluded; a learned method's call includes its ICP "
        "refinement and, in an isolated call, loading its weights), one call at a time per core "
        "with the threads shown. For the learned methods, network CPU ms is the forward alone, "
        "GMAC its multiply-accumulates for this config and these point counts (networks/cost), "
        "floor ms those MACs at the single-thread fp32 GEMM rate measured in the same process, "
        "and x floor = network CPU ms / floor ms; points: the points per cloud the timed calls "
        "had (source and target, from the rows; a range where they differ). Ours: CPU {}; BLAS of the learned methods: "
        "{}; classical methods: {}; CPU only (no GPU rows measured). Paper (ms): {}",
        cpu_model, learned.empty() ? "none measured" : learned, blas,
        paper.at("tables").at("table6_inference_time").value("caption", std::string()));
    t.caption += "\nAs the rows record it: " + SetsEnvironment(sets) + ".";
    return t;
}

}  // namespace regbench
