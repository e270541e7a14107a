// The contract every registered method keeps (tests/baselines/method_contract.hpp), run on every
// registered method: methods added to the registry join here.
#include <string>
#include <vector>

#include "runners/registry.hpp"
#include "tests/baselines/method_contract.hpp"

namespace regbench {
namespace {

using testing::MethodContract;
using testing::MethodNames;

INSTANTIATE_TEST_SUITE_P(AllMethods, MethodContract, ::testing::ValuesIn(MethodNames()),
                         testing::MethodContractName);

TEST(Registry, UnknownMethodListsKnownNames) {
    try {
        CreateMethod("no-such-method");
        FAIL() << "expected std::invalid_argument";
    } catch (const std::invalid_argument& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("unknown method 'no-such-method'"), std::string::npos) << what;
        EXPECT_NE(what.find("icp"), std::string::npos) << what;
    }
}

TEST(Registry, NamesAreUnique) {
    const auto names = MethodNames();
    for (std::size_t i = 0; i < names.size(); ++i) {
        for (std::size_t j = i + 1; j < names.size(); ++j) EXPECT_NE(names[i], names[j]);
    }
}

}  // namespace
}  // namespace regbench
