#pragma once
// Where regbench's data lives: the CGAL corpus and meshes, the shipped checkpoints (models/)
// and the paper's tables (paper/). One lookup for all of them, so a binary finds its data from
// any working directory.
#include <string>

namespace regbench {

/// $REGBENCH_DATA_DIR if set; else $REGBENCH_SOURCE_DIR/data if set; else the data/ folder of
/// the source tree the binary was built from, if it exists; else ./data.
std::string DataDir();

}  // namespace regbench
