#include "reports/html_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "reports/row_access.hpp"
#include "reports/statistics.hpp"

namespace regbench {
namespace {

// A colour-blind-friendly palette (Okabe-Ito), cycled over methods.
const std::vector<std::string> kPalette = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                           "#E69F00", "#56B4E9", "#000000", "#F0E442",
                                           "#999999", "#882255", "#44AA99", "#117733"};

std::string Escape(const std::string& s) {
    std::string out;
    for (char c : s) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

std::string Colour(std::size_t i) { return kPalette[i % kPalette.size()]; }

/// Which of the four dash patterns / marker shapes method i gets: i mod 4, shifted by one for
/// each round of the palette, so no two of the first 48 methods share colour and pattern.
std::size_t Variant(std::size_t i) { return (i + i / kPalette.size()) % 4; }

/// Dash pattern of curve i (solid, dashed, dotted, dash-dot), so curves differ by more than
/// colour (grey-scale print, colour-blind readers).
std::string Dash(std::size_t i) {
    static const char* kDashes[] = {"", "7 3", "2 2", "9 3 2 3"};
    return kDashes[Variant(i)];
}

/// Marker of method i centred at (x, y) with radius r: circle, square, triangle or diamond.
std::string Marker(std::size_t i, double x, double y, double r, const std::string& extra = "") {
    const std::string fill = "fill=\"" + Colour(i) + "\"" + extra;
    switch (Variant(i)) {
        case 0:
            return fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" {}/>", x, y, r,
                               fill);
        case 1:
            return fmt::format(
                "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" {}/>", x - r,
                y - r, 2 * r, 2 * r, fill);
        case 2:
            return fmt::format("<path d=\"M{:.1f} {:.1f}L{:.1f} {:.1f}L{:.1f} {:.1f}Z\" {}/>", x,
                               y - 1.2 * r, x + 1.1 * r, y + 0.8 * r, x - 1.1 * r, y + 0.8 * r,
                               fill);
        default:
            return fmt::format(
                "<path d=\"M{:.1f} {:.1f}L{:.1f} {:.1f}L{:.1f} {:.1f}L{:.1f} {:.1f}Z\" {}/>", x,
                y - 1.3 * r, x + 1.3 * r, y, x, y + 1.3 * r, x - 1.3 * r, y, fill);
    }
}

}  // namespace

std::vector<double> NiceTicks(double lo, double hi, bool log) {
    std::vector<double> ticks;
    if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return {lo};
    if (log && lo > 0.0) {
        // Powers of ten in range; with fewer than two, their 2x and 5x as well.
        for (double m : {1.0, 2.0, 5.0}) {
            for (int e = static_cast<int>(std::floor(std::log10(lo)));
                 e <= static_cast<int>(std::ceil(std::log10(hi))); ++e) {
                const double v = m * std::pow(10.0, e);
                if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) ticks.push_back(v);
            }
            if (ticks.size() >= 2) break;
        }
        std::sort(ticks.begin(), ticks.end());
        return ticks;
    }
    // Linear: a step of 1, 2 or 5 times a power of ten giving about four intervals.
    const double raw = (hi - lo) / 4.0;
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    const double norm = raw / mag;
    const double step = (norm < 1.5 ? 1.0 : norm < 3.0 ? 2.0 : norm < 7.0 ? 5.0 : 10.0) * mag;
    for (double k = std::ceil(lo / step - 1e-9); k * step <= hi + 1e-9 * step; k += 1.0) {
        const double v = k * step;
        ticks.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
    }
    return ticks;
}

namespace {

/// A plot frame: maps data coordinates into a w x h SVG with margins, draws axes and ticks.
struct Plot {
    double x0, x1, y0, y1;
    bool log_x = false;
    int w = 540, h = 340, left = 56, right = 150, top = 20, bottom = 44;

    /// A frame whose legend has room for `entries` lines (14 px each).
    static Plot For(double x0, double x1, double y0, double y1, std::size_t entries) {
        Plot p{x0, x1, y0, y1};
        p.h = std::max(p.h, p.top + 14 * static_cast<int>(entries) + p.bottom);
        return p;
    }

    double X(double x) const {
        const double a = log_x ? std::log10(x0) : x0, b = log_x ? std::log10(x1) : x1;
        const double v = log_x ? std::log10(std::max(x, 1e-12)) : x;
        return left + (v - a) / (b - a) * (w - left - right);
    }
    double Y(double y) const { return h - bottom - (y - y0) / (y1 - y0) * (h - top - bottom); }

    std::string Open(const std::string& xlabel, const std::string& ylabel) const {
        std::string s = fmt::format(
            "<svg width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\" role=\"img\">"
            "<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#fff\"/>",
            w, h, w, h, w, h);
        s += fmt::format(
            "<line x1=\"{0}\" y1=\"{1}\" x2=\"{2}\" y2=\"{1}\" stroke=\"#333\"/>"
            "<line x1=\"{0}\" y1=\"{1}\" x2=\"{0}\" y2=\"{3}\" stroke=\"#333\"/>",
            left, h - bottom, w - right, top);
        for (const double xv : NiceTicks(x0, x1, log_x)) {
            s += fmt::format(
                "<text x=\"{:.1f}\" y=\"{}\" font-size=\"11\" text-anchor=\"middle\">{:g}</text>",
                X(xv), h - bottom + 19, xv);  // below the y axis's lowest label
        }
        for (const double yv : NiceTicks(y0, y1, false)) {
            s += fmt::format(
                "<text x=\"{}\" y=\"{:.1f}\" font-size=\"11\" text-anchor=\"end\">{:g}</text>"
                "<line x1=\"{}\" y1=\"{:.1f}\" x2=\"{}\" y2=\"{:.1f}\" stroke=\"#eee\"/>",
                left - 4, Y(yv) + 4, yv, left + 1, Y(yv), w - right, Y(yv));
        }
        s +=
            fmt::format("<text x=\"{}\" y=\"{}\" font-size=\"12\" text-anchor=\"middle\">{}</text>",
                        (left + w - right) / 2, h - 8, Escape(xlabel));
        s += fmt::format(
            "<text x=\"14\" y=\"{}\" font-size=\"12\" text-anchor=\"middle\" "
            "transform=\"rotate(-90 14 {})\">{}</text>",
            (top + h - bottom) / 2, (top + h - bottom) / 2, Escape(ylabel));
        return s;
    }

    /// Colour swatches, or (lines) short strokes with each curve's dash pattern.
    std::string Legend(const std::vector<std::string>& names, bool lines = false) const {
        std::string s;
        for (std::size_t i = 0; i < names.size(); ++i) {
            const int y = top + 14 * static_cast<int>(i) + 6;
            if (lines) {
                s += fmt::format(
                    "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{}\" "
                    "stroke-width=\"1.6\" stroke-dasharray=\"{}\"/>",
                    w - right + 4, y - 3, w - right + 20, y - 3, Colour(i), Dash(i));
            } else {
                s += Marker(i, w - right + 14, y - 3, 4.0);
            }
            s += fmt::format("<text x=\"{}\" y=\"{}\" font-size=\"11\">{}</text>", w - right + 24,
                             y + 1, Escape(names[i]));
        }
        return s;
    }
};

/// The row's mae_r; a null (failed) one as +inf, so the error CDF keeps it in its denominator
/// and the gallery ranks it worst.
double MaeROrInf(const ResultRow& r) {
    const double e = r.metrics.mae_r;
    return std::isfinite(e) ? e : std::numeric_limits<double>::infinity();
}

/// The metric of every row of `method`, +inf where it is not finite (a miss at any threshold).
std::vector<double> MetricOf(const std::vector<ResultRow>& rows, const std::string& method,
                             const MetricField& metric) {
    std::vector<double> v;
    for (const ResultRow* r : RowsOf(rows, method)) {
        v.push_back(metric.Of(r->metrics).value_or(std::numeric_limits<double>::infinity()));
    }
    return v;
}

/// The section's success-rate curves, one figure each, captioned with their AUC per method.
std::string CurveFigures(const HtmlSection& sec) {
    std::string s;
    for (const SuccessCurve& c : sec.curves) {
        const bool degrees = c.metric == "rre" || c.metric == "mae_r";
        const std::string unit = degrees ? " [deg]" : "";
        std::string auc;
        for (const auto& method : MethodOrder(sec.rows)) {
            std::vector<double> e;
            for (const ResultRow* r : RowsOf(sec.rows, method)) {
                e.push_back(FindMetric(c.metric).Of(r->metrics).value_or(std::nan("")));
            }
            auc += fmt::format("{}{} {:.3f}", auc.empty() ? "" : ", ", method, SuccessAuc(e, c.max));
        }
        s += "<figure>" + SuccessCurveSvg(sec.rows, c, c.metric + " threshold" + unit) +
             "<figcaption>" +
             Escape(fmt::format("Success rate: fraction of all pairs with {} below x; AUC on "
                                "[0, {:g}]: {}",
                                c.metric, c.max, auc)) +
             "</figcaption></figure>";
    }
    return s;
}

}  // namespace

std::string TableToHtml(const Table& t, TableForm form) {
    std::string s = t.title.empty() ? "" : "<h3>" + Escape(t.title) + "</h3>\n";
    if (!t.caption.empty()) s += "<p class=\"cap\">" + Escape(t.caption) + "</p>\n";
    for (const auto& src : DataSources(t)) {
        s += "<p class=\"src\">Data source: " + Escape(src) + "</p>\n";
    }
    const ShownTable shown = ShowTable(t, form, " ± ");
    // Wide tables scroll inside their own box instead of widening the page.
    s += "<div class=\"tw\"><table><tr><th>" + Escape(t.row_header) + "</th>";
    for (const auto& c : shown.columns) {
        s += std::string(c.paper ? "<th class=\"paper\">" : "<th>") + Escape(c.header) + "</th>";
    }
    s += "</tr>\n";
    for (std::size_t r = 0; r < shown.labels.size(); ++r) {
        s += "<tr><td>" + Escape(shown.labels[r]) + "</td>";
        for (std::size_t c = 0; c < shown.columns.size(); ++c) {
            std::string text = Escape(shown.cells[r][c]);
            if (shown.best[r][c]) text = "<b>" + text + "</b>";
            s += std::string(shown.columns[c].paper ? "<td class=\"paper\">" : "<td>") + text +
                 "</td>";
        }
        s += "</tr>\n";
    }
    s += "</table></div>\n";
    for (const auto& n : t.notes) s += "<p class=\"note\">" + Escape(n) + "</p>\n";
    return s;
}

std::string ErrorCdfSvg(const std::vector<ResultRow>& rows, double max_deg) {
    return SuccessCurveSvg(rows, {"mae_r", max_deg}, "MAE(R) threshold [deg]");
}

std::string SuccessCurveSvg(const std::vector<ResultRow>& rows, const SuccessCurve& curve,
                            const std::string& axis) {
    const MetricField& metric = FindMetric(curve.metric);
    const double max_deg = curve.max;
    const auto methods = MethodOrder(rows);
    const Plot p = Plot::For(0.0, max_deg, 0.0, 1.0, methods.size());
    std::string s = p.Open(axis, "fraction of pairs below");
    for (std::size_t i = 0; i < methods.size(); ++i) {
        std::vector<double> v = MetricOf(rows, methods[i], metric);
        std::sort(v.begin(), v.end());
        // A step curve: after the k-th smallest error the fraction is k / n.
        std::string pts = fmt::format("{:.1f},{:.1f}", p.X(0), p.Y(0));
        double frac = 0.0;
        for (std::size_t k = 0; k < v.size() && v[k] <= max_deg; ++k) {
            pts += fmt::format(" {:.1f},{:.1f}", p.X(v[k]), p.Y(frac));
            frac = static_cast<double>(k + 1) / static_cast<double>(v.size());
            pts += fmt::format(" {:.1f},{:.1f}", p.X(v[k]), p.Y(frac));
        }
        pts += fmt::format(" {:.1f},{:.1f}", p.X(max_deg), p.Y(frac));
        s += fmt::format(
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.6\" "
            "stroke-dasharray=\"{}\"/>",
            pts, Colour(i), Dash(i));
    }
    return s + p.Legend(methods, /*lines=*/true) + "</svg>";
}

std::string ErrorVsOverlapSvg(const std::vector<ResultRow>& rows) {
    const auto methods = MethodOrder(rows);
    double ymax = 1.0;
    for (const auto& r : rows) {
        if (std::isfinite(r.metrics.mae_r)) ymax = std::max(ymax, r.metrics.mae_r);
    }
    const Plot p = Plot::For(0.0, 1.0, 0.0, ymax * 1.05, methods.size());
    std::string s = p.Open("measured overlap, min(source, target)", "MAE(R) [deg]");
    std::size_t drawn = 0;
    for (std::size_t i = 0; i < methods.size(); ++i) {
        for (const ResultRow* r : RowsOf(rows, methods[i])) {
            const auto overlap = MeasuredOverlap(*r);
            if (!overlap || !std::isfinite(r->metrics.mae_r)) continue;
            ++drawn;
            s += Marker(i, p.X(*overlap), p.Y(r->metrics.mae_r), 2.4, " fill-opacity=\"0.6\"");
        }
    }
    if (drawn == 0) {
        s += fmt::format(
            "<text x=\"{}\" y=\"{}\" font-size=\"12\" text-anchor=\"middle\">rows "
            "carry no overlap ratios</text>",
            p.w / 2, p.h / 2);
    }
    return s + p.Legend(methods) + "</svg>";
}

std::string TimeVsAccuracySvg(const std::vector<ResultRow>& rows) {
    const auto methods = MethodOrder(rows);
    std::vector<double> t(methods.size()), e(methods.size());
    double tmin = 1e300, tmax = 0.0, emax = 1.0;
    for (std::size_t i = 0; i < methods.size(); ++i) {
        std::vector<double> secs, err;
        for (const ResultRow* r : RowsOf(rows, methods[i])) {
            secs.push_back(std::max(r->result.seconds, 1e-6));
            if (std::isfinite(r->metrics.mae_r)) err.push_back(r->metrics.mae_r);
        }
        t[i] = SampleMedian(secs);
        e[i] = SampleMean(err);
        if (std::isfinite(t[i])) {
            tmin = std::min(tmin, t[i]);
            tmax = std::max(tmax, t[i]);
        }
        if (std::isfinite(e[i])) emax = std::max(emax, e[i]);
    }
    if (!(tmax > 0.0)) tmin = 1e-4, tmax = 1.0;
    Plot p = Plot::For(std::pow(10.0, std::floor(std::log10(tmin))),
                       std::pow(10.0, std::ceil(std::log10(tmax)) + (tmin == tmax ? 1 : 0)), 0.0,
                       emax * 1.1, methods.size());
    p.log_x = true;
    std::string s = p.Open("median seconds per pair (log)", "mean MAE(R) [deg]");
    // Each method a marker of its own colour and shape, named in the legend: labels beside
    // the points overlapped wherever methods are close in time and accuracy.
    for (std::size_t i = 0; i < methods.size(); ++i) {
        if (!std::isfinite(t[i]) || !std::isfinite(e[i])) continue;
        s += Marker(i, p.X(t[i]), p.Y(e[i]), 4.5, " fill-opacity=\"0.85\"");
    }
    return s + p.Legend(methods) + "</svg>";
}

std::string PairProjectionSvg(const Pair& pair, const Transform& estimate, int max_points) {
    const int size = 360;
    PointCloud aligned(pair.source.rows(), 3);
    for (Eigen::Index i = 0; i < pair.source.rows(); ++i) {
        aligned.row(i) = (estimate.topLeftCorner<3, 3>() * pair.source.row(i).transpose() +
                          estimate.topRightCorner<3, 1>())
                             .transpose();
    }
    // One square frame around target, source and aligned source (x-y projection).
    double lo = 1e300, hi = -1e300;
    for (const PointCloud* c :
         {&pair.target, &pair.source, static_cast<const PointCloud*>(&aligned)}) {
        if (c->rows() == 0) continue;
        lo = std::min({lo, c->col(0).minCoeff(), c->col(1).minCoeff()});
        hi = std::max({hi, c->col(0).maxCoeff(), c->col(1).maxCoeff()});
    }
    if (!(hi > lo)) lo = -1, hi = 1;
    const auto px = [&](double v) { return 6 + (v - lo) / (hi - lo) * (size - 12); };
    std::string s = fmt::format(
        "<svg width=\"{0}\" height=\"{0}\" viewBox=\"0 0 {0} {0}\" role=\"img\"><rect x=\"0\" "
        "y=\"0\" width=\"{0}\" height=\"{0}\" fill=\"#fff\" stroke=\"#ccc\"/>",
        size);
    const auto draw = [&](const PointCloud& c, const char* colour) {
        const Eigen::Index step = std::max<Eigen::Index>(1, c.rows() / std::max(1, max_points));
        std::string d;
        for (Eigen::Index i = 0; i < c.rows(); i += step) {
            // Tiny squares as one path: far smaller than one <circle> per point.
            d += fmt::format("M{:.0f} {:.0f}h3v3h-3z", px(c(i, 0)), size - px(c(i, 1)));
        }
        s += fmt::format("<path d=\"{}\" fill=\"{}\"/>", d, colour);
    };
    draw(pair.target, "#888888");
    draw(pair.source, "#D55E00");
    draw(aligned, "#009E73");
    return s + "</svg>";
}

std::string PaperTablesLegend(const std::vector<Table>& tables) {
    bool merged = false, alone = false;
    for (const auto& t : tables) {
        for (const auto& c : ShowTable(t, TableForm::kCompact, " ± ").columns) {
            merged |= c.with_paper;
            alone |= c.paper;
        }
    }
    std::string s = "Measured here";
    if (merged) {
        s += "; in parentheses after a measured value, the paper's as published (a column whose "
             "header ends in \"(paper)\" holds both)";
    }
    if (alone) s += "; grey columns: the paper's numbers alone, as published";
    return s + ". Bold: the best measured cell of a column.";
}

// The page top to bottom (head and style, the paper tables, one section per experiment):
// long because it is the document, each part a few lines of markup.
std::string RenderHtmlReport(const HtmlReportOptions& o) {
    std::string s =
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" +
        Escape(o.title) +
        "</title>\n<style>body{font-family:sans-serif;margin:24px;max-width:1400px;color:#222}"
        "table{border-collapse:collapse;margin:8px 0 4px 0;font-size:13px}"
        ".tw{max-width:100%;overflow-x:auto}"
        "td,th{border:1px solid #ccc;padding:3px 7px;text-align:right}"
        "td:first-child,th:first-child{text-align:left}th{background:#f2f2f2}"
        ".src{font-weight:bold;color:#8a4b00;margin:4px "
        "0}.paper{color:#777}.cap,.note{font-size:12px;color:#444;max-width:1100px}"
        ".plots{display:flex;flex-wrap:wrap;gap:12px}.gal{display:flex;flex-wrap:wrap;gap:8px}"
        "figure{margin:0;font-size:11px}h2{border-bottom:2px solid #ddd;margin-top:32px}"
        "</style></head><body>\n<h1>" +
        Escape(o.title) + "</h1>\n";
    for (const auto& p : o.intro) s += "<p>" + Escape(p) + "</p>\n";
    if (!o.tables.empty()) {
        s += "<h2>The paper's tables</h2>\n<p class=\"note\">" + Escape(PaperTablesLegend(o.tables)) +
             "</p>\n";
        for (const auto& t : o.tables) s += TableToHtml(t);
    }
    for (const auto& sec : o.sections) {
        s += "<h2>" + Escape(sec.title) + "</h2>\n";
        if (!sec.description.empty()) s += "<p class=\"cap\">" + Escape(sec.description) + "</p>\n";
        s += "<div class=\"plots\"><figure>" + ErrorCdfSvg(sec.rows, o.cdf_max_deg) +
             "<figcaption>Error CDF: fraction of pairs with MAE(R) below x</figcaption></figure>"
             "<figure>" +
             ErrorVsOverlapSvg(sec.rows) +
             "<figcaption>MAE(R) vs the pair's measured overlap</figcaption></figure><figure>" +
             TimeVsAccuracySvg(sec.rows) +
             "<figcaption>Accuracy vs time (median seconds per pair, one thread)</figcaption>"
             "</figure>" +
             CurveFigures(sec) + "</div>\n";
        for (const auto& t : sec.tables) s += TableToHtml(t);
        if (!sec.pair_lookup) continue;
        s += "<h3>Worst pairs per method</h3><p class=\"note\">x-y projection; grey target, "
             "red source (its own frame), green source under the method's estimate.</p>\n";
        for (const auto& method : MethodOrder(sec.rows)) {
            std::vector<const ResultRow*> mine = RowsOf(sec.rows, method);
            std::stable_sort(mine.begin(), mine.end(), [](const ResultRow* a, const ResultRow* b) {
                return MaeROrInf(*a) > MaeROrInf(*b);
            });
            s += "<h4>" + Escape(method) + "</h4><div class=\"gal\">";
            for (int k = 0; k < o.gallery_per_method && k < static_cast<int>(mine.size()); ++k) {
                const Pair* pair = sec.pair_lookup(*mine[k]);
                if (pair == nullptr) continue;
                s += "<figure>" +
                     PairProjectionSvg(*pair, mine[k]->result.T_target_source, o.gallery_points) +
                     fmt::format(
                         "<figcaption>pair {} ({}), MAE(R) {:.2f}°, {}</figcaption></figure>",
                         mine[k]->pair, Escape(mine[k]->shape), MaeROrInf(*mine[k]),
                         Escape(ToString(mine[k]->status)));
            }
            s += "</div>\n";
        }
    }
    s += "</body></html>\n";
    return s;
}

}  // namespace regbench
