#pragma once
// Time per call in `report` (issue 54 item 2): median and 95th percentile of wall and CPU
// seconds per method, with the threads, CPU model and library versions the rows record.
#include <string>
#include <vector>

#include "reports/paper_report.hpp"
#include "reports/report.hpp"
#include "reports/table.hpp"
#include "runners/result_row.hpp"

namespace regbench {

/// One line: the threads per call, the CPU model and the library versions (Eigen, Open3D,
/// LibTorch and its BLAS) the rows' `machine` records, each value once (several, joined by
/// " / ", when the rows were run on several machines or builds); rows without them (written
/// before rows recorded them, or by `score`) are counted as such.
std::string DescribeEnvironment(const std::vector<const ResultRow*>& rows);

/// DescribeEnvironment of every row of the sets (Tab. 6's caption).
std::string SetsEnvironment(const std::vector<ResultSet>& sets);

/// A table "<pairs file>:timing" with a row per summary row: pairs, median and 95th
/// percentile of wall seconds and of CPU seconds per call (MethodSummary; SampleQuantile's
/// linear definition), threads. Its caption names the clocks and the table's environment.
Table TimingTable(const ReportTable& table);

/// TimingTable of each, captions numbered "Table i of n. " when there are several.
std::vector<Table> TimingTables(const std::vector<ReportTable>& tables);

}  // namespace regbench
