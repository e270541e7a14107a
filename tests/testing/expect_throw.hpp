#pragma once
// The one "call, expect an exception, check its message" helper the tests share, in place of
// hand-written try / FAIL / catch / find blocks.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace regbench::testing {

/// Expects `fn` to throw an exception derived from E whose message contains every one of
/// `needles` (each convertible to std::string); a missing exception or needle fails the test,
/// naming what was expected and the message.
template <typename E = std::runtime_error, typename Fn, typename... Needles>
void ExpectThrowsWith(Fn&& fn, const Needles&... needles) {
    static_assert(sizeof...(Needles) > 0, "name at least one expected substring");
    try {
        fn();
        ADD_FAILURE() << "no exception; expected one naming"
                      << ((" '" + std::string(needles) + "'") + ...);
    } catch (const E& e) {
        const std::string what = e.what();
        for (const std::string& needle : {std::string(needles)...}) {
            EXPECT_NE(what.find(needle), std::string::npos) << "no '" << needle << "' in: " << what;
        }
    }
}

}  // namespace regbench::testing
