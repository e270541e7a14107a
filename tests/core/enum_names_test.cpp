#include "core/enum_names.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace regbench {
namespace {

enum class Colour { kRed, kGreen, kBlue };
constexpr EnumName<Colour> kColourNames[] = {
    {Colour::kRed, "red"},
    {Colour::kGreen, "green"},
    {Colour::kBlue, "blue"},
};

TEST(EnumNames, NamesAndValuesRoundTrip) {
    for (const auto& e : kColourNames) {
        EXPECT_STREQ(EnumToString(kColourNames, e.value), e.name);
        EXPECT_EQ(ParseEnum(kColourNames, "colour", e.name), e.value);
    }
    EXPECT_EQ(FindEnum(kColourNames, "blue"), Colour::kBlue);
    EXPECT_FALSE(FindEnum(kColourNames, "Blue").has_value());  // case-sensitive
}

TEST(EnumNames, ListJoinsTheNamesInTableOrder) {
    EXPECT_EQ(EnumNameList(kColourNames), "red, green, blue");
    EXPECT_EQ(EnumNameList(kColourNames, ", ", " or "), "red, green or blue");
}

TEST(EnumNames, ParseErrorNamesTheKindTheValueAndTheChoices) {
    try {
        ParseEnum(kColourNames, "colour", "mauve", "paint: ");
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "paint: unknown colour 'mauve' (known: red, green, blue)");
    }
}

TEST(EnumNames, AValueMissingFromTheTableIsALogicError) {
    constexpr EnumName<Colour> kPartial[] = {{Colour::kRed, "red"}};
    EXPECT_THROW(EnumToString(kPartial, Colour::kBlue), std::logic_error);
}

}  // namespace
}  // namespace regbench
