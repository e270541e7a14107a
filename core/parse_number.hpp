#pragma once
// Whole-string number parsing for text from users and files, locale-independent
// (std::from_chars): one place instead of each caller wrapping std::stod in a try block and
// checking how much of the text it consumed.
//
//   ParseNumber<double>("1.5") -> 1.5        ParseNumber<double>("1.5x") -> nullopt
//   ParseNumber<double>("+2")  -> 2          ParseNumber<int>("+2")      -> nullopt
//   ParseNumber<unsigned>("-1") -> nullopt   ParseNumber<double>(" 1")   -> nullopt
#include <charconv>
#include <optional>
#include <string_view>
#include <system_error>
#include <type_traits>

namespace regbench {

/// The number `text` spells in full, or nullopt (empty text, trailing characters, out of
/// range). Floating-point values may start with '+' (as std::stod allows) and may be "inf" or
/// "nan": callers that need finite values check. Whole numbers are digits with an optional
/// '-' (refused for unsigned types).
template <class T>
std::optional<T> ParseNumber(std::string_view text) {
    const char* begin = text.data();
    const char* const end = begin + text.size();
    if constexpr (std::is_floating_point_v<T>) {
        if (begin != end && *begin == '+') ++begin;
    }
    T value{};
    const auto [stop, ec] = std::from_chars(begin, end, value);
    if (begin == end || ec != std::errc() || stop != end) return std::nullopt;
    return value;
}

}  // namespace regbench
