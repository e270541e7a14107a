#pragma once
// Strict number options: CLI11 alone turns "-1" into 2^64-1 for an unsigned option and reads
// "1e23" into a count; these validators run on the text before any conversion.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>

#include "core/parse_number.hpp"
#include "core/threads.hpp"

namespace regbench::app {

namespace detail {

/// A decimal number as the real-valued options take it: no leading '+' ("+1" refused), else
/// what ParseNumber reads ("nan" and "inf" pass here; the validators refuse them).
inline std::optional<double> PlainReal(const std::string& s) {
    return s.empty() || s[0] == '+' ? std::nullopt : ParseNumber<double>(s);
}

/// The validator `name` of every option below: the texts `ok` accepts pass, any other is
/// refused with "expected <what>, got '<text>'".
template <class Ok>
CLI::Validator Expecting(const std::string& name, const std::string& what, Ok ok) {
    return CLI::Validator(
        [what, ok](std::string& s) -> std::string {
            return ok(s) ? "" : "expected " + what + ", got '" + s + "'";
        },
        name);
}

/// A finite number between `lo` and `hi`, both excluded (`open`) or both included.
inline CLI::Validator Interval(double lo, double hi, bool open) {
    char range[64];
    std::snprintf(range, sizeof(range), open ? "(%g, %g)" : "[%g, %g]", lo, hi);
    return Expecting("REAL", std::string("a number in ") + range,
                     [lo, hi, open](const std::string& s) {
                         const auto v = PlainReal(s);
                         if (!v || !std::isfinite(*v)) return false;
                         return open ? *v > lo && *v < hi : *v >= lo && *v <= hi;
                     });
}

}  // namespace detail

/// Digits only, fitting in 64 bits: refuses "2.5", "-1", "1e23", "+3", "0x10", "".
inline CLI::Validator WholeNumber() {
    return detail::Expecting("UINT", "a whole number >= 0 (digits only)", [](const std::string& s) {
        return ParseNumber<std::uint64_t>(s).has_value();
    });
}

/// Digits only, at least 1: refuses "0" as well as everything WholeNumber refuses.
inline CLI::Validator PositiveWholeNumber() {
    return detail::Expecting("UINT>=1", "a whole number >= 1", [](const std::string& s) {
        const auto v = ParseNumber<std::uint64_t>(s);
        return v && *v > 0;
    });
}

/// An OpenMP thread count: a whole number in [1, kMaxThreads] (core/threads.hpp); 10^9 made
/// libgomp kill the process.
inline CLI::Validator ThreadCount() {
    return detail::Expecting(
        "THREADS", "a whole number in [1, " + std::to_string(kMaxThreads) + "]",
        [](const std::string& s) {
            const auto v = ParseNumber<std::uint64_t>(s);
            return v && *v >= 1 && *v <= static_cast<std::uint64_t>(kMaxThreads);
        });
}

/// A finite decimal number >= 0 ("-1", "nan", "inf", "1s" refused).
inline CLI::Validator NonNegativeReal() {
    return detail::Expecting("REAL>=0", "a finite number >= 0", [](const std::string& s) {
        const auto v = detail::PlainReal(s);
        return v && std::isfinite(*v) && *v >= 0;
    });
}

/// A finite decimal number > 0 ("0", "-1", "nan", "inf" refused).
inline CLI::Validator PositiveReal() {
    return detail::Expecting("REAL>0", "a finite number > 0", [](const std::string& s) {
        const auto v = detail::PlainReal(s);
        return v && std::isfinite(*v) && *v > 0;
    });
}

/// A finite number strictly between `lo` and `hi` (a significance level, a fraction).
inline CLI::Validator OpenInterval(double lo, double hi) { return detail::Interval(lo, hi, true); }

/// A finite number in the closed interval [lo, hi] (a tolerance with a sensible ceiling).
inline CLI::Validator ClosedInterval(double lo, double hi) {
    return detail::Interval(lo, hi, false);
}

/// Parses "i/n" with 0 <= i < n, digits only ("1/2x", "-1/2", "1/0" refused).
inline void ParseShard(const std::string& text, int* index, int* count) {
    const auto slash = text.find('/');
    const auto parse = [&](const std::string& part, int* out) {
        const std::optional<int> v =
            part.empty() || part[0] == '-' ? std::nullopt : ParseNumber<int>(part);
        if (v) *out = *v;
        return v.has_value();
    };
    if (slash == std::string::npos || !parse(text.substr(0, slash), index) ||
        !parse(text.substr(slash + 1), count) || *count < 1 || *index >= *count) {
        throw CLI::ValidationError(
            "--shard must be i/n with whole numbers 0 <= i < n <= 2147483647, got '" + text + "'");
    }
}

}  // namespace regbench::app
