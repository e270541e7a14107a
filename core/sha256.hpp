#pragma once
// SHA-256 (FIPS 180-4) of bytes or of a file, as lower-case hex: the content hash recorded for
// imported checkpoints and for dataset files.
#include <string>

namespace regbench {

std::string Sha256Hex(const std::string& bytes);
/// Throws std::runtime_error naming the file when it cannot be read.
std::string Sha256File(const std::string& path);

}  // namespace regbench
