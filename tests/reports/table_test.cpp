// The Table API keys every cell by its column (issue 40, item 3): a cell given for one column
// shows under that column's header whatever the order, and a cell for a column the table does
// not have is refused when the row is built, not written under another header.
#include "reports/table.hpp"

#include <gtest/gtest.h>

#include "tests/testing/expect_throw.hpp"

namespace regbench {
namespace {

Table TwoColumns() {
    Table t("t", "", "");
    t.columns = {{"a", "A", CellSource::kMeasured, Better::kNone, 1},
                 {"b", "B", CellSource::kMeasured, Better::kNone, 1}};
    return t;
}

TEST(Table, CellsLandUnderTheirColumnWhateverTheOrderGiven) {
    Table t = TwoColumns();
    t.AddRow("x", {{"b", MeasuredCell(2.0, 1)}, {"a", MeasuredCell(1.0, 1)}});
    t.AddRow("y", {{"b", MeasuredCell(4.0, 1)}});  // no cell under "a": shown as "-"
    // By hand: A holds 1.0 and "-", B holds 2.0 and 4.0.
    EXPECT_EQ(TableToMarkdown(t),
              "| method | A | B |\n|---|---:|---:|\n| x | 1.0 | 2.0 |\n| y | - | 4.0 |\n");
    EXPECT_DOUBLE_EQ(t.rows[0].Get("a").value, 1.0);
    EXPECT_FALSE(t.rows[1].Get("a").HasValue());
    const auto j = TablesToJson({t});
    ASSERT_EQ(j.size(), 4u);
    EXPECT_EQ(j[1]["column"], "b");
    EXPECT_DOUBLE_EQ(j[1]["value"].get<double>(), 2.0);
}

TEST(Table, ACellForAnUnknownColumnIsRefusedNamingIt) {
    Table t = TwoColumns();
    testing::ExpectThrowsWith<std::logic_error>(
        [&] {
            t.AddRow("x", {{"a", MeasuredCell(1.0, 1)}, {"c", MeasuredCell(3.0, 1)}});
        },
        "table 't'", "row 'x'", "no column 'c'");
    EXPECT_TRUE(t.rows.empty());  // nothing half-added
}

TEST(Table, TwoCellsForOneColumnAndRepeatedColumnKeysAreRefused) {
    Table t = TwoColumns();
    testing::ExpectThrowsWith<std::logic_error>(
        [&] {
            t.AddRow("x", {{"a", MeasuredCell(1.0, 1)}, {"a", MeasuredCell(3.0, 1)}});
        },
        "two cells for column 'a'");
    t.columns.push_back(t.columns.front());
    testing::ExpectThrowsWith<std::logic_error>([&] { t.AddRow("x", {}); }, "two columns 'a'");
}

}  // namespace
}  // namespace regbench
