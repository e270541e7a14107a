// ParseConfig (core/params.hpp): the rules of model, training, protocol and experiment configs.
// Expected values are the numbers the JSON spells (by hand); out-of-range integers must be
// refused before they wrap (3e9 in an int used to come back as -1294967296).
#include <gtest/gtest.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "core/params.hpp"

namespace regbench {
namespace {

struct SmallConfig {
    int count = 3;
    std::uint64_t seed = 0;
    double scale = 1.0;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(SmallConfig, count, seed, scale)

std::string Refusal(const nlohmann::json& j) {
    try {
        ParseConfig<SmallConfig>(j, "small config");
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "";
}

TEST(ParseConfig, WholeNumbersWithinTheFieldsTypeAreRead) {
    const auto c = ParseConfig<SmallConfig>(
        nlohmann::json::parse(R"({"count": 2.0, "seed": 9007199254740992})"), "small config");
    EXPECT_EQ(c.count, 2);
    EXPECT_EQ(c.seed, 9007199254740992u);  // 2^53, the one rule's limit
    EXPECT_EQ(c.scale, 1.0);
    EXPECT_EQ(ParseConfig<SmallConfig>({{"count", -2147483648LL}}, "small config").count,
              -2147483648LL);
}

TEST(ParseConfig, IntegersTheFieldCannotHoldAreRefusedByName) {
    for (const nlohmann::json& bad :
         {nlohmann::json(3e9), nlohmann::json(3000000000LL), nlohmann::json(-2147483649LL)}) {
        const std::string why = Refusal({{"count", bad}});
        EXPECT_NE(why.find("small config: parameter 'count' is out of range"), std::string::npos)
            << bad << ": " << why;
        EXPECT_NE(why.find(bad.dump()), std::string::npos) << why;
    }
    EXPECT_NE(Refusal({{"seed", -1}}).find("'seed' is out of range"), std::string::npos);
    EXPECT_NE(Refusal({{"count", 2.5}}).find("'count' must be a whole number"), std::string::npos);
    EXPECT_NE(Refusal({{"cout", 2}}).find("unknown parameter 'cout'"), std::string::npos);
}

}  // namespace
}  // namespace regbench
