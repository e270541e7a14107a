#include "reports/timing.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "reports/row_access.hpp"

namespace regbench {
namespace {

/// The distinct values of `get` over the rows in first-seen order, joined by " / ", and how
/// many rows had none ("").
std::string Distinct(const std::vector<const ResultRow*>& rows,
                     std::string (*get)(const ResultRow&), std::size_t* missing) {
    std::vector<std::string> seen;
    for (const ResultRow* r : rows) {
        const std::string v = get(*r);
        if (v.empty()) {
            ++*missing;
        } else if (std::find(seen.begin(), seen.end(), v) == seen.end()) {
            seen.push_back(v);
        }
    }
    std::string out;
    for (const auto& v : seen) out += (out.empty() ? "" : " / ") + v;
    return out.empty() ? "not recorded" : out;
}

std::string MachineString(const ResultRow& r, const char* key) {
    const auto it = r.machine.find(key);
    return it != r.machine.end() && it->is_string() ? it->get<std::string>() : "";
}

std::string Libraries(const ResultRow& r) {
    const auto it = r.machine.find("libraries");
    if (it == r.machine.end() || !it->is_object()) return "";
    std::string out;
    for (const auto& [key, name] : {std::pair{"libtorch", "LibTorch"}, std::pair{"open3d", "Open3D"},
                                    std::pair{"eigen", "Eigen"}, std::pair{"blas", "LibTorch's BLAS"}}) {
        const auto v = it->find(key);
        if (v != it->end() && v->is_string()) {
            out += fmt::format("{}{} {}", out.empty() ? "" : ", ", name, v->get<std::string>());
        }
    }
    return out;
}

Column TimeCol(const std::string& key, const std::string& header) {
    return {key, header, CellSource::kMeasured, Better::kLower, kSecondsDecimals, CiStyle::kHidden};
}

}  // namespace

std::string DescribeEnvironment(const std::vector<const ResultRow*>& rows) {
    std::size_t no_cpu = 0, no_libs = 0, no_threads = 0;
    const std::string threads = Distinct(
        rows, [](const ResultRow& r) { return std::to_string(r.threads); }, &no_threads);
    const std::string cpu =
        Distinct(rows, [](const ResultRow& r) { return MachineString(r, "cpu"); }, &no_cpu);
    const std::string libs = Distinct(rows, Libraries, &no_libs);
    std::string out = fmt::format("threads per call {}; CPU {}; libraries {}", threads, cpu, libs);
    const std::size_t missing = std::max(no_cpu, no_libs);
    if (missing > 0) {
        out += fmt::format(" ({} of {} rows record no CPU model or library versions: written by "
                           "`score` or before rows recorded them)",
                           missing, rows.size());
    }
    return out;
}

std::string SetsEnvironment(const std::vector<ResultSet>& sets) {
    std::vector<const ResultRow*> rows;
    for (const ResultSet& s : sets) {
        for (const ResultRow& r : s.rows) rows.push_back(&r);
    }
    return DescribeEnvironment(rows);
}

Table TimingTable(const ReportTable& rt) {
    Table t;
    t.id = rt.data.pairs_file + ":" + ToString(rt.euler) + ":timing";
    t.caption = fmt::format(
        "Time per pair on `{}`: wall (steady clock) and CPU seconds of the method's own call "
        "(the harness's loading, metrics and I/O excluded; CPU of the calling thread, or of the "
        "process for threaded calls), median and 95th percentile over all pairs (numpy.quantile's "
        "linear definition), failed calls included; \"-\": the rows recorded no CPU time. "
        "Measured with {}.",
        rt.data.pairs_file, rt.environment);
    t.columns = {{"pairs", "pairs", CellSource::kMeasured, Better::kNone, 0},
                 TimeCol("median_seconds", "median wall s"),
                 TimeCol("p95_seconds", "p95 wall s"),
                 TimeCol("median_cpu_seconds", "median CPU s"),
                 TimeCol("p95_cpu_seconds", "p95 CPU s"),
                 {"threads", "threads", CellSource::kMeasured, Better::kNone, 0}};
    for (const MethodSummary& s : rt.methods) {
        const std::size_t n = s.pairs;
        t.AddRow(s.label, {{"pairs", MeasuredCell(static_cast<double>(n), n)},
                           {"median_seconds", MeasuredCell(s.median_seconds, n)},
                           {"p95_seconds", MeasuredCell(s.p95_seconds, n)},
                           {"median_cpu_seconds", MeasuredCell(s.median_cpu_seconds, n)},
                           {"p95_cpu_seconds", MeasuredCell(s.p95_cpu_seconds, n)},
                           {"threads", MeasuredCell(static_cast<double>(s.threads), n)}});
    }
    return t;
}

std::vector<Table> TimingTables(const std::vector<ReportTable>& tables) {
    std::vector<Table> out;
    for (std::size_t i = 0; i < tables.size(); ++i) {
        out.push_back(TimingTable(tables[i]));
        if (tables.size() > 1) {
            out.back().caption =
                fmt::format("Table {} of {}. ", i + 1, tables.size()) + out.back().caption;
        }
    }
    return out;
}

}  // namespace regbench
