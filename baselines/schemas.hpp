#pragma once
// The methods' parameter schemas, baselines/<stem>.schema.json, compiled into the binary by
// cmake/EmbedSchemas.cmake (core/param_schema.hpp describes the format).

namespace regbench {

/// The text of baselines/<stem>.schema.json, e.g. BaselineSchema("icp_pl"); throws
/// std::logic_error when there is no such file.
const char* BaselineSchema(const char* stem);

}  // namespace regbench
