#pragma once
// JSON from files and the command line is parsed with a nesting limit: nlohmann's parser is
// iterative, but copying, comparing and printing a value recurse, so a line nested a million
// levels deep (a few MB of '[') overflowed the stack and `compare` died by SIGSEGV.
#include <cstddef>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <string_view>

#include "core/input_file.hpp"

namespace regbench {

/// True when `text` is well-formed UTF-8 (no overlong forms, surrogates or code points above
/// U+10FFFF): what nlohmann::json requires of every string it prints.
inline bool IsValidUtf8(std::string_view text) {
    std::size_t i = 0;
    const std::size_t n = text.size();
    while (i < n) {
        const auto c = static_cast<unsigned char>(text[i]);
        std::size_t len = 0;
        unsigned lo = 0x80, hi = 0xBF;  // allowed range of the second byte
        if (c < 0x80) {
            ++i;
            continue;
        } else if (c >= 0xC2 && c <= 0xDF) {
            len = 1;
        } else if (c >= 0xE0 && c <= 0xEF) {
            len = 2;
            if (c == 0xE0) lo = 0xA0;
            if (c == 0xED) hi = 0x9F;
        } else if (c >= 0xF0 && c <= 0xF4) {
            len = 3;
            if (c == 0xF0) lo = 0x90;
            if (c == 0xF4) hi = 0x8F;
        } else {
            return false;
        }
        if (i + len >= n) return false;  // truncated sequence
        for (std::size_t k = 1; k <= len; ++k) {
            const auto b = static_cast<unsigned char>(text[i + k]);
            const unsigned min = k == 1 ? lo : 0x80, max = k == 1 ? hi : 0xBF;
            if (b < min || b > max) return false;
        }
        i += len + 1;
    }
    return true;
}

/// Deeper than any file regbench writes (result rows nest 4 levels, pair-file attributes 3).
inline constexpr int kMaxJsonDepth = 64;

/// nlohmann::json::parse(text) refusing nesting deeper than kMaxJsonDepth with
/// std::runtime_error "<where>: JSON nested deeper than 64 levels". Syntax errors still throw
/// nlohmann::json::parse_error, as parse() does.
inline nlohmann::json ParseJsonBounded(std::string_view text, const std::string& where) {
    const nlohmann::json::parser_callback_t limit =
        [&where](int depth, nlohmann::json::parse_event_t event, nlohmann::json&) {
            if (depth >= kMaxJsonDepth && (event == nlohmann::json::parse_event_t::object_start ||
                                           event == nlohmann::json::parse_event_t::array_start)) {
                throw std::runtime_error(where + ": JSON nested deeper than " +
                                         std::to_string(kMaxJsonDepth) + " levels");
            }
            return true;
        };
    return nlohmann::json::parse(text, limit);
}

/// The JSON file `path`, parsed as ParseJsonBounded does. Throws std::runtime_error
/// "<what>: cannot open" or "<what>: not valid JSON: <why>", `what` naming the file's role.
inline nlohmann::json ReadJsonFileBounded(const std::string& path, const std::string& what) {
    RequireRegularFile(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error(what + ": cannot open");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    try {
        return ParseJsonBounded(text, what);
    } catch (const std::exception& e) {
        throw std::runtime_error(what + ": not valid JSON: " + e.what());
    }
}

}  // namespace regbench
