#pragma once
// HDF5 benchmark files: write atomically (temporary name, then rename), read all or one pair.
#include <string>

#include "protocols/pair.hpp"

namespace regbench {

/// Writes `set` to `path` via `path.tmp` + rename. Throws std::runtime_error naming the path.
void WritePairFile(const std::string& path, const PairSet& set);
/// Reads every pair. Throws std::runtime_error naming the path (and pair) on any problem.
PairSet ReadPairFile(const std::string& path);
/// Number of pairs in the file, without reading clouds.
std::size_t CountPairs(const std::string& path);

}  // namespace regbench
