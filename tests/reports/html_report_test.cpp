#include "reports/html_report.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>

#include "reports/breakdown.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;

/// A small pair: a ring of points and its copy shifted by 0.3 along x.
Pair RingPair() {
    Pair p;
    p.source.resize(200, 3);
    for (int i = 0; i < 200; ++i) {
        const double a = 2 * M_PI * i / 200.0;
        p.source.row(i) << std::cos(a), 0.5 * std::sin(a), 0.1 * std::sin(3 * a);
    }
    p.target = p.source;
    p.target.col(0).array() += 0.3;
    p.T_gt(0, 3) = 0.3;
    return p;
}

std::vector<ResultRow> Rows() {
    std::vector<ResultRow> rows;
    for (int k = 0; k < 30; ++k) {
        for (const std::string m : {"icp", "cpd", "svr"}) {
            const double e = (m == "icp" ? 10.0 : m == "cpd" ? 3.0 : 6.0) + std::fmod(k * 1.7, 5.0);
            ResultRow r;
            r.pair = static_cast<std::size_t>(k);
            r.method = m;
            r.shape = "ring";
            r.category = k % 2 ? "a" : "b";
            r.result.seconds = m == "cpd" ? 0.05 : 0.005;
            r.source_overlap_ratio = 0.5 + 0.015 * k;
            r.target_overlap_ratio = 0.55 + 0.01 * k;
            r.result.T_target_source(0, 3) = 0.1 * (k % 3);
            r.metrics.mae_r = e;
            r.metrics.mae_t = e / 100;
            r.metrics.ccd = 0.05;
            r.metrics.rre = e;
            r.metrics.rte = e / 50;
            rows.push_back(r);
        }
    }
    return rows;
}

std::string Render() {
    static const Pair pair = RingPair();
    HtmlReportOptions o;
    o.title = "test report";
    o.intro = {"made by html_report_test"};
    HtmlSection s;
    s.title = "ring pairs";
    s.rows = Rows();
    s.tables = {DistributionTable(s.rows, BreakdownOptions{}),
                RecallTable(s.rows, BreakdownOptions{})};
    s.pair_lookup = [](const ResultRow&) { return &pair; };
    o.sections = {s};
    return RenderHtmlReport(o);
}

TEST(HtmlReport, IsSelfContained) {
    const std::string html = Render();
    // No network: no URL scheme at all, no scripts, no external resources or fonts.
    EXPECT_EQ(html.find("http"), std::string::npos);
    EXPECT_EQ(html.find("//"), std::string::npos);
    EXPECT_EQ(html.find("<script"), std::string::npos);
    EXPECT_EQ(html.find("src="), std::string::npos);
    EXPECT_EQ(html.find("url("), std::string::npos);
    EXPECT_EQ(html.find("@import"), std::string::npos);
    // Plots and gallery are inline SVG: 3 plots + 3 methods x 2 worst pairs.
    std::size_t svgs = 0;
    for (auto p = html.find("<svg"); p != std::string::npos; p = html.find("<svg", p + 1)) ++svgs;
    EXPECT_EQ(svgs, 3u + 6u);
    EXPECT_NE(html.find("Worst pairs per method"), std::string::npos);
    EXPECT_NE(html.find("<table>"), std::string::npos);
}

// Issue 54: a section's success curves are drawn with their AUC per method in the caption;
// expected AUCs from numpy.trapz of the step curve on 1500001 points of [0, 15] over 15 (icp
// 0.19000016, cpd 0.65666684, svr 0.45666680), shown at 3 decimals.
TEST(HtmlReport, SuccessCurvesShowTheirAuc) {
    HtmlReportOptions o;
    HtmlSection s;
    s.title = "ring pairs";
    s.rows = Rows();
    s.curves = {{"rre", 15.0}};
    o.sections = {s};
    const std::string html = RenderHtmlReport(o);
    EXPECT_NE(html.find("fraction of all pairs with rre below x; AUC on [0, 15]: icp 0.190, "
                        "cpd 0.657, svr 0.457</figcaption>"),
              std::string::npos);
    EXPECT_NE(html.find("rre threshold [deg]"), std::string::npos);
}

TEST(HtmlReport, WideTablesScrollInTheirBoxAndCurvesDifferByDash) {
    const std::string html = Render();
    // Every table sits in a box that scrolls sideways (at 1200 px a wide table no longer
    // widens the page).
    std::size_t tables = 0, boxed = 0;
    for (auto p = html.find("<table>"); p != std::string::npos; p = html.find("<table>", p + 1)) {
        ++tables;
        boxed += html.compare(p - 16, 16, "<div class=\"tw\">") == 0;
    }
    EXPECT_GT(tables, 0u);
    EXPECT_EQ(boxed, tables);
    EXPECT_NE(html.find(".tw{max-width:100%;overflow-x:auto}"), std::string::npos);
    // The CDF's second and third curves are dashed and dotted as well as coloured.
    const std::string cdf = ErrorCdfSvg(Rows(), 45.0);
    EXPECT_NE(cdf.find("stroke-dasharray=\"7 3\""), std::string::npos) << cdf;
    EXPECT_NE(cdf.find("stroke-dasharray=\"2 2\""), std::string::npos) << cdf;
    // Round ticks: the CDF's x axis 0-45 degrees at 0, 10, ..., 40 (step 10 = 45/4 rounded to
    // 1, 2 or 5 times a power of ten), not 0, 11.25, 22.5, ...
    EXPECT_NE(cdf.find(">10</text>"), std::string::npos) << cdf;
    EXPECT_EQ(cdf.find(">11.2"), std::string::npos) << cdf;
}

/// A table with a measured MAE(R) column, the paper's beside it (merged in the compact form)
/// and, with `lone`, a paper column of its own (Tab. 6's "paper ms": no measured twin).
Table PaperTable(bool lone) {
    Table t("paper_table", "Tab. X", "");
    t.columns = {{"mae_r", "MAE(R)", CellSource::kMeasured, Better::kLower, 2},
                 {"paper:mae_r", "paper MAE(R)", CellSource::kPaper, Better::kNone, 2}};
    if (lone) t.columns.push_back({"paper:ms", "paper ms", CellSource::kPaper, Better::kNone, 0});
    Cell ours, paper, ms;
    ours.value = 7.25;
    paper.value = 3.5;
    paper.source = ms.source = CellSource::kPaper;
    ms.value = 41;
    RowCells cells = {{"mae_r", ours}, {"paper:mae_r", paper}};
    if (lone) cells.push_back({"paper:ms", ms});
    t.AddRow("ogmm", cells);
    return t;
}

// Issue 54, item 7: the legend said "Grey columns: the paper's numbers", but the compact HTML
// merges each paper column into the measured one before it ("7.25 (3.5)", header "(paper)"):
// no grey column is left. The legend says what the page shows.
TEST(HtmlReport, PaperLegendSaysWhatTheTablesShow) {
    HtmlReportOptions o;
    o.title = "legend";
    o.tables = {PaperTable(false)};
    const std::string html = RenderHtmlReport(o);
    EXPECT_NE(html.find("<td><b>7.25 (3.5)</b></td>"), std::string::npos) << html;
    EXPECT_EQ(html.find("class=\"paper\""), std::string::npos) << html;
    EXPECT_NE(html.find("in parentheses after a measured value, the paper's as published"),
              std::string::npos)
        << html;
    EXPECT_EQ(html.find("rey column"), std::string::npos) << html;
    // A paper column with no measured twin stays a column of its own, in grey, and the legend
    // then names grey columns too.
    o.tables = {PaperTable(true)};
    const std::string lone = RenderHtmlReport(o);
    EXPECT_NE(lone.find("<td class=\"paper\">41</td>"), std::string::npos) << lone;
    EXPECT_NE(lone.find("grey columns: the paper's numbers alone"), std::string::npos) << lone;
}

TEST(HtmlReport, NiceTicksAreRoundNumbers) {
    // Hand-computed: 45/4 = 11.25 -> step 10; 1/4 = 0.25 -> step 0.2; 18.9/4 = 4.7 -> step 5.
    EXPECT_EQ(NiceTicks(0.0, 45.0, false), (std::vector<double>{0, 10, 20, 30, 40}));
    const std::vector<double> unit = NiceTicks(0.0, 1.0, false);
    ASSERT_EQ(unit.size(), 6u);
    EXPECT_NEAR(unit[3], 0.6, 1e-12);
    EXPECT_EQ(NiceTicks(0.0, 18.9, false), (std::vector<double>{0, 5, 10, 15}));
    // Log axis: the powers of ten in range; within one decade, 1-2-5 steps.
    EXPECT_EQ(NiceTicks(0.004, 3.0, true), (std::vector<double>{0.01, 0.1, 1.0}));
    EXPECT_EQ(NiceTicks(0.15, 0.9, true), (std::vector<double>{0.2, 0.5}));
}

/// 13 methods of nearly the same time and accuracy (their labels would pile up in the
/// accuracy-time plot), one with a long name, 10 pairs each.
std::vector<ResultRow> ThirteenMethods() {
    std::vector<ResultRow> rows;
    for (int m = 0; m < 13; ++m) {
        for (int k = 0; k < 10; ++k) {
            ResultRow r;
            r.pair = static_cast<std::size_t>(k);
            r.method = m == 12 ? "open3d-py-icp-csv-long" : "method" + std::to_string(m);
            r.shape = "ring";
            r.category = "a";
            r.result.seconds = 0.01 * (1.0 + 0.01 * m);
            r.source_overlap_ratio = r.target_overlap_ratio = 0.6;
            r.metrics.mae_r = 5.0 + 0.02 * m + 0.3 * k;
            r.metrics.mae_t = r.metrics.rte = 0.01 * r.metrics.mae_r;
            r.metrics.ccd = 0.05;
            r.metrics.rre = r.metrics.mae_r;
            rows.push_back(r);
        }
    }
    return rows;
}

/// Runs `html` in headless Chromium at 1200 x 1000 with a script (this test's only) that
/// reports, once laid out: the page wider than the window, a table box that must scroll, and
/// any two <text> labels of one plot whose boxes overlap. Returns "ok" or the problems.
std::string LayoutProblems(const std::string& html, const fs::path& dir) {
    const std::string script = R"(<script>
const bad = [];
const doc = document.documentElement;
if (doc.scrollWidth > window.innerWidth) bad.push('page ' + doc.scrollWidth + ' px wide');
document.querySelectorAll('.tw').forEach((b, i) => {
  if (b.scrollWidth > b.clientWidth + 1) bad.push('table ' + i + ' scrolls: ' + b.scrollWidth);
});
document.querySelectorAll('svg').forEach((svg, n) => {
  const boxes = [...svg.querySelectorAll('text')].map(t => [t.textContent, t.getBoundingClientRect()]);
  for (let i = 0; i < boxes.length; ++i) for (let j = i + 1; j < boxes.length; ++j) {
    const [a, p] = boxes[i], [b, q] = boxes[j];
    if (p.left < q.right - 1 && q.left < p.right - 1 && p.top < q.bottom - 1 && q.top < p.bottom - 1)
      bad.push('plot ' + n + ': "' + a + '" overlaps "' + b + '"');
  }
});
document.body.setAttribute('data-layout', bad.length ? bad.join('; ') : 'ok');
</script>)";
    std::string page = html;
    page.insert(page.rfind("</body>"), script);
    fs::create_directories(dir / "profile");
    std::ofstream(dir / "check.html") << page;
    const std::string cmd =
        "timeout 180 chromium --headless --no-sandbox --disable-gpu "
        "--disable-background-networking --disable-component-update --disable-sync "
        "--no-first-run --user-data-dir=" +
        (dir / "profile").string() + " --window-size=1200,1000 --dump-dom file://" +
        (dir / "check.html").string() + " > " + (dir / "dom.html").string() + " 2> " +
        (dir / "chromium.log").string();
    if (std::system(cmd.c_str()) != 0)
        return "chromium failed; see " + (dir / "chromium.log").string();
    std::ifstream in(dir / "dom.html");
    const std::string dom((std::istreambuf_iterator<char>(in)), {});
    const std::string key = "data-layout=\"";
    const auto at = dom.find(key);
    if (at == std::string::npos) return "no layout result in the DOM";
    const auto start = at + key.size();
    return dom.substr(start, dom.find('"', start) - start);
}

TEST(HtmlReport, ThirteenMethodsFitAt1200PxWithoutOverlappingLabels) {
    // Issue 41 item 4, checked in the browser: no sideways scrolling at 1200 px (compact tables),
    // no label over another in any plot (the accuracy-time plot named its points beside them).
    static const Pair pair = RingPair();
    const std::vector<ResultRow> rows = ThirteenMethods();
    HtmlReportOptions o;
    o.title = "thirteen methods";
    HtmlSection s;
    s.title = "close methods";
    s.rows = rows;
    s.tables = {DistributionTable(rows, BreakdownOptions{}), StatusTable(rows),
                RecallTable(rows, BreakdownOptions{})};
    s.pair_lookup = [](const ResultRow&) { return &pair; };
    o.sections = {s};
    const fs::path dir =
        fs::temp_directory_path() / ("regbench_layout_" + std::to_string(::getpid()));
    EXPECT_EQ(LayoutProblems(RenderHtmlReport(o), dir), "ok");
    fs::remove_all(dir);
}

TEST(HtmlReport, ThirteenMethodsGetDistinctColourAndMarkerPairs) {
    // Method 12 repeats method 0's colour (12 in the palette); its marker and dash differ.
    const std::string plot = TimeVsAccuracySvg(ThirteenMethods());
    // Circles for methods 0, 4 and 8 (marker (i + i / 12) mod 4 = 0), in the plot and the
    // legend; the rest squares, triangles, diamonds.
    std::size_t circles = 0;
    for (auto p = plot.find("<circle"); p != std::string::npos; p = plot.find("<circle", p + 1))
        ++circles;
    EXPECT_EQ(circles, 6u) << plot;
    const std::string cdf = ErrorCdfSvg(ThirteenMethods(), 45.0);
    const std::string solid = "stroke=\"#0072B2\" stroke-width=\"1.6\" stroke-dasharray=\"\"";
    std::size_t solid_blue = 0;
    for (auto p = cdf.find(solid); p != std::string::npos; p = cdf.find(solid, p + 1)) ++solid_blue;
    EXPECT_EQ(solid_blue, 2u);  // method 0's curve and its legend line; not method 12's
}

/// Decoded 8-bit RGB(A) PNG (the only kind Chromium writes for screenshots).
struct Image {
    int width = 0, height = 0, channels = 0;
    std::vector<unsigned char> pixels;
};

std::uint32_t BigEndian(const unsigned char* p) {
    return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) |
           p[3];
}

/// A minimal PNG reader (PNG spec, sections 5, 9 and 11): chunks, zlib-inflated IDAT, the five
/// scanline filters. Non-interlaced 8-bit truecolour only; throws otherwise.
Image DecodePng(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    const std::vector<unsigned char> b((std::istreambuf_iterator<char>(in)), {});
    const unsigned char sig[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    if (b.size() < 8 || !std::equal(sig, sig + 8, b.begin())) throw std::runtime_error("not a PNG");
    Image img;
    std::vector<unsigned char> idat;
    for (std::size_t at = 8; at + 8 <= b.size();) {
        const std::uint32_t len = BigEndian(&b[at]);
        const std::string type(b.begin() + at + 4, b.begin() + at + 8);
        const unsigned char* data = &b[at + 8];
        if (type == "IHDR") {
            img.width = static_cast<int>(BigEndian(data));
            img.height = static_cast<int>(BigEndian(data + 4));
            if (data[8] != 8 || (data[9] != 2 && data[9] != 6) || data[12] != 0)
                throw std::runtime_error("unsupported PNG format");
            img.channels = data[9] == 6 ? 4 : 3;
        } else if (type == "IDAT") {
            idat.insert(idat.end(), data, data + len);
        }
        at += 12 + len;
    }
    const std::size_t stride = static_cast<std::size_t>(img.width) * img.channels;
    std::vector<unsigned char> raw((stride + 1) * img.height);
    uLongf raw_size = raw.size();
    if (uncompress(raw.data(), &raw_size, idat.data(), idat.size()) != Z_OK ||
        raw_size != raw.size())
        throw std::runtime_error("bad IDAT");
    img.pixels.resize(stride * img.height);
    const int bpp = img.channels;
    for (int y = 0; y < img.height; ++y) {
        const unsigned char filter = raw[y * (stride + 1)];
        const unsigned char* src = &raw[y * (stride + 1) + 1];
        unsigned char* out = &img.pixels[y * stride];
        const unsigned char* up = y > 0 ? &img.pixels[(y - 1) * stride] : nullptr;
        for (std::size_t x = 0; x < stride; ++x) {
            const int a = x >= static_cast<std::size_t>(bpp) ? out[x - bpp] : 0;
            const int u = up ? up[x] : 0;
            const int c = (up && x >= static_cast<std::size_t>(bpp)) ? up[x - bpp] : 0;
            int pred = 0;
            switch (filter) {
                case 0:
                    pred = 0;
                    break;
                case 1:
                    pred = a;
                    break;
                case 2:
                    pred = u;
                    break;
                case 3:
                    pred = (a + u) / 2;
                    break;
                case 4: {
                    const int p = a + u - c, pa = std::abs(p - a), pb = std::abs(p - u),
                              pc = std::abs(p - c);
                    pred = (pa <= pb && pa <= pc) ? a : (pb <= pc ? u : c);
                    break;
                }
                default:
                    throw std::runtime_error("bad filter");
            }
            out[x] = static_cast<unsigned char>(src[x] + pred);
        }
    }
    return img;
}

TEST(HtmlReport, RendersInHeadlessChromium) {
    const fs::path dir =
        fs::temp_directory_path() / ("regbench_html_" + std::to_string(::getpid()));
    fs::create_directories(dir / "profile");
    const fs::path html = dir / "report.html";
    const fs::path png = dir / "shot.png";
    std::ofstream(html) << Render();
    // Debian's chromium (scripts/install_deps.sh); everything that could reach the network off.
    const std::string cmd =
        "timeout 180 chromium --headless --no-sandbox --disable-gpu "
        "--disable-background-networking --disable-component-update --disable-sync "
        "--no-first-run --user-data-dir=" +
        (dir / "profile").string() + " --screenshot=" + png.string() +
        " --window-size=1200,1600 file://" + html.string() + " > " +
        (dir / "chromium.log").string() + " 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << "chromium failed; see " << dir / "chromium.log";
    const Image img = DecodePng(png.string());
    EXPECT_EQ(img.width, 1200);
    EXPECT_EQ(img.height, 1600);
    // Not blank: a good share of non-white pixels and the plot palette's colours.
    std::size_t ink = 0;
    std::set<std::uint32_t> colours;
    for (std::size_t i = 0; i + 2 < img.pixels.size(); i += img.channels) {
        const unsigned char r = img.pixels[i], g = img.pixels[i + 1], b = img.pixels[i + 2];
        if (r < 240 || g < 240 || b < 240) ++ink;
        colours.insert((r << 16) | (g << 8) | b);
    }
    const double ink_fraction = static_cast<double>(ink) / (img.width * img.height);
    EXPECT_GT(ink_fraction, 0.01);
    EXPECT_GT(colours.size(), 20u);
    // The Okabe-Ito blue (#0072B2) of the first method's curve is on screen.
    EXPECT_TRUE(colours.count(0x0072B2)) << colours.size() << " colours";
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench
