#pragma once
// A content hash of a pair set's arrays, so result rows can say exactly which pairs they were
// computed on (two files with the same name but other pairs get different hashes).
#include <string>

#include "protocols/pair.hpp"

namespace regbench {

/// "fnv1a64:<16 hex digits>" over, per pair in order: the clouds (point count, then x, y, z of
/// every point as IEEE-754 bits), T_gt (row-major), both overlap label arrays, shape and
/// category. Provenance and per-pair meta are not hashed: they describe the data, they are not
/// the data. Deterministic across runs and machines (bytes are fed in a fixed order).
std::string PairSetContentHash(const PairSet& set);

}  // namespace regbench
