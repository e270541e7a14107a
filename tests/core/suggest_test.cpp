#include "core/suggest.hpp"

#include <gtest/gtest.h>

namespace regbench {
namespace {

// Expected distances by hand (optimal string alignment): kitten -> sitting is the textbook
// Levenshtein example (k->s, e->i, insert g: 3); a swap of two adjacent letters is one edit.
TEST(Suggest, EditDistanceCountsAnAdjacentSwapAsOneEdit) {
    EXPECT_EQ(EditDistance("kitten", "sitting"), 3u);
    EXPECT_EQ(EditDistance("cdp", "cpd"), 1u);
    EXPECT_EQ(EditDistance("cdp", "icp"), 2u);
    EXPECT_EQ(EditDistance("ICP", "icp"), 0u);
    EXPECT_EQ(EditDistance("", "fgr"), 3u);
}

TEST(Suggest, ClosestNamePrefersTheSwapAndRefusesFarNames) {
    const std::vector<std::string> known = {"identity", "icp", "cpd", "fgr"};
    EXPECT_EQ(ClosestName("cdp", known), "cpd");
    EXPECT_EQ(ClosestName("iden", known), "identity");  // an abbreviation
    EXPECT_EQ(ClosestName("zzzzzz", known), "");
}

}  // namespace
}  // namespace regbench
