#include "reports/report.hpp"

#include <gtest/gtest.h>

namespace regbench {
namespace {

nlohmann::json Row(const std::string& method,
                   double mae_r,
                   double mae_t,
                   double seconds,
                   const std::string& status = "ok") {
    return {{"method", method},
            {"status", status},
            {"seconds", seconds},
            {"metrics",
             {{"mae_r", mae_r},
              {"mae_t", mae_t},
              {"mse_r", mae_r * mae_r},
              {"mse_t", mae_t * mae_t},
              {"rre", mae_r * 2},
              {"rte", mae_t * 2},
              {"ccd", 0.05},
              {"chamfer", 0.01}}}};
}

TEST(Report, AggregatesPerMethodByHand) {
    const std::vector<nlohmann::json> rows = {Row("a", 0.5, 0.01, 1.0), Row("a", 2.0, 0.01, 3.0),
                                              Row("a", 0.2, 0.5, 2.0, "failed"),
                                              Row("b", 10.0, 0.2, 0.1)};
    const auto s = Summarize(rows, ReportOptions{});
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s[0].method, "a");
    EXPECT_EQ(s[0].pairs, 3u);
    EXPECT_EQ(s[0].failed, 1u);
    EXPECT_NEAR(s[0].mae_r.mean, 0.9, 1e-12);
    EXPECT_NEAR(s[0].rmse_r, std::sqrt((0.25 + 4.0 + 0.04) / 3.0), 1e-12);
    // recall@(1, 0.1): only the first row (0.5 deg, 0.01).
    EXPECT_NEAR(s[0].recall, 1.0 / 3.0, 1e-12);
    EXPECT_NEAR(s[0].median_seconds, 2.0, 1e-12);
    EXPECT_LE(s[0].mae_r.lo, s[0].mae_r.mean);
    EXPECT_GE(s[0].mae_r.hi, s[0].mae_r.mean);
    EXPECT_NEAR(s[1].recall, 0.0, 1e-12);
    const std::string md = FormatMarkdown(s, ReportOptions{});
    EXPECT_NE(md.find("| a | 3 | 1 | 0.9000 |"), std::string::npos) << md;
    EXPECT_NE(md.find("| b |"), std::string::npos);
    EXPECT_NE(FormatCsv(s).find("a,3,1,0.9"), std::string::npos);
}

TEST(Report, MedianOfEvenCountAveragesTheMiddle) {
    const auto s = Summarize(
        {Row("a", 1, 0, 1.0), Row("a", 1, 0, 4.0), Row("a", 1, 0, 2.0), Row("a", 1, 0, 3.0)},
        ReportOptions{});
    EXPECT_NEAR(s[0].median_seconds, 2.5, 1e-12);
}

TEST(Report, RowWithoutMetricsIsRejected) {
    EXPECT_THROW(Summarize({{{"method", "a"}, {"pair", 0}}}, ReportOptions{}), std::runtime_error);
}

}  // namespace
}  // namespace regbench
