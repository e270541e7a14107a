// ParseNumber: whole-string, locale-independent parsing. Expected values are the numbers the
// texts spell (by hand); the refusals are the texts std::stod would have half-read.
#include "core/parse_number.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>

namespace regbench {
namespace {

TEST(ParseNumber, ReadsWholeTextsOnly) {
    EXPECT_EQ(ParseNumber<double>("1.5"), 1.5);
    EXPECT_EQ(ParseNumber<double>("-2e-3"), -0.002);
    EXPECT_EQ(ParseNumber<double>("+2"), 2.0);  // std::stod accepted a leading '+'
    EXPECT_EQ(ParseNumber<int>("-7"), -7);
    EXPECT_EQ(ParseNumber<std::uint64_t>("18446744073709551615"), UINT64_MAX);
    for (const std::string text : {"", " 1", "1 ", "1.5x", "0x10", "+", "1e", "--1"}) {
        EXPECT_FALSE(ParseNumber<double>(text)) << "'" << text << "'";
    }
    EXPECT_FALSE(ParseNumber<int>("+2"));  // whole numbers: digits and '-' only
    EXPECT_FALSE(ParseNumber<int>("2.5"));
    EXPECT_FALSE(ParseNumber<std::uint64_t>("-1"));                    // not 2^64 - 1
    EXPECT_FALSE(ParseNumber<std::uint64_t>("18446744073709551616"));  // 2^64: out of range
}

TEST(ParseNumber, LeavesNonFiniteValuesToTheCaller) {
    EXPECT_TRUE(std::isinf(*ParseNumber<double>("inf")));
    EXPECT_TRUE(std::isnan(*ParseNumber<double>("nan")));
}

}  // namespace
}  // namespace regbench
