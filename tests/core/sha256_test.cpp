#include "core/sha256.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace regbench {
namespace {

// Expected digests: the FIPS 180-4 examples (NIST CSRC "SHA256.pdf"), also printed by
// coreutils' sha256sum for the same bytes.
TEST(Sha256, MatchesTheStandardsExamples) {
    EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
    EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    EXPECT_EQ(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
              "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
    EXPECT_EQ(Sha256Hex(std::string(1000000, 'a')),
              "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

// The same digests from bytes given in pieces of every size from 1 to 130 (across the 64-byte
// blocks and the padding's 56-byte boundary).
TEST(Sha256, PiecesGiveTheDigestOfTheWhole) {
    const std::string million(1000000, 'a');
    for (std::size_t piece = 1; piece <= 130; ++piece) {
        Sha256 h;
        for (std::size_t at = 0; at < million.size(); at += piece) {
            h.Update(million.data() + at, std::min(piece, million.size() - at));
        }
        ASSERT_EQ(h.Hex(), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0")
            << piece;
    }
    const std::string two = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";  // 56 bytes
    Sha256 h;
    h.Update(two.data(), 55);
    h.Update(two.data() + 55, 1);
    EXPECT_EQ(h.Hex(), "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Sha256, UnreadableFileIsNamed) {
    try {
        Sha256File("/nonexistent/dir/x.h5");
        FAIL();
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/x.h5"), std::string::npos);
    }
}

}  // namespace
}  // namespace regbench
