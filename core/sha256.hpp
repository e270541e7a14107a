#pragma once
// SHA-256 (FIPS 180-4) of bytes or of a file, as lower-case hex: the content hash recorded for
// imported checkpoints and for dataset files.
#include <cstddef>
#include <cstdint>
#include <string>

namespace regbench {

/// SHA-256 of bytes given in pieces (a file read in chunks): Update with each piece in order,
/// then Hex once.
class Sha256 {
public:
    void Update(const void* data, std::size_t n);
    std::string Hex();

private:
    void Block(const unsigned char* p);
    std::uint32_t h_[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                           0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
    unsigned char buf_[64] = {};
    std::size_t fill_ = 0;
    std::uint64_t total_ = 0;
};

std::string Sha256Hex(const std::string& bytes);
/// Throws std::runtime_error naming the file when it cannot be read.
std::string Sha256File(const std::string& path);

}  // namespace regbench
