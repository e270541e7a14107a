#pragma once
// Enum <-> name conversion from one table of {value, name} pairs, so that an enum's names are
// written once instead of in a ToString switch and again in a Parse function. (Enums that are
// method parameters declare theirs with REGBENCH_CHOICES, below.)
//
//   constexpr EnumName<Colour> kColourNames[] = {{Colour::kRed, "red"}, {Colour::kBlue, "blue"}};
//   EnumToString(kColourNames, Colour::kRed)    -> "red"
//   ParseEnum(kColourNames, "colour", "green")  -> throws std::invalid_argument
//                                                  "unknown colour 'green' (known: red, blue)"
#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/suggest.hpp"

namespace regbench {

template <class Enum>
struct EnumName {
    Enum value;
    const char* name;
};

/// The name of `value`; throws std::logic_error when the table lacks it (a programming error).
template <class Enum, std::size_t N>
const char* EnumToString(const EnumName<Enum> (&table)[N], Enum value) {
    for (const auto& e : table) {
        if (e.value == value) return e.name;
    }
    throw std::logic_error("enum value without a name");
}

/// The value named `name`, if the table has it.
template <class Enum, std::size_t N>
std::optional<Enum> FindEnum(const EnumName<Enum> (&table)[N], const std::string& name) {
    for (const auto& e : table) {
        if (name == e.name) return e.value;
    }
    return std::nullopt;
}

/// The table's names in order, joined by `separator`, the last two by `last_separator`.
template <class Enum, std::size_t N>
std::string EnumNameList(const EnumName<Enum> (&table)[N], const std::string& separator = ", ",
                         const std::string& last_separator = ", ") {
    std::string list;
    for (std::size_t i = 0; i < N; ++i) {
        if (i > 0) list += i + 1 == N ? last_separator : separator;
        list += table[i].name;
    }
    return list;
}

/// The value named `name`; otherwise throws std::invalid_argument
/// "<prefix>unknown <what> '<name>' (did you mean '<close name>'? known: <names>)".
template <class Enum, std::size_t N>
Enum ParseEnum(const EnumName<Enum> (&table)[N], const std::string& what, const std::string& name,
               const std::string& prefix = "") {
    if (const auto value = FindEnum(table, name)) return *value;
    std::vector<std::string> known;
    for (const auto& e : table) known.emplace_back(e.name);
    throw std::invalid_argument(prefix + "unknown " + what + " '" + name + "' (" +
                                DidYouMean(name, known) + "known: " + EnumNameList(table) + ")");
}

/// The names of a choice enum, after the enum: REGBENCH_CHOICES(Centre, {{Centre::kMean,
/// "mean"}, {Centre::kMedian, "median"}}). Defines ChoicesOf(Centre{}) (the table, in this
/// order) and nlohmann's to_json/from_json (NLOHMANN_JSON_SERIALIZE_ENUM); parameters are
/// read strictly (an unknown name is an error listing the names).
#define REGBENCH_CHOICES(Enum, ...)                                            \
    inline const std::vector<EnumName<Enum>>& ChoicesOf(Enum /*tag*/) {        \
        static const std::vector<EnumName<Enum>> regbench_names = __VA_ARGS__; \
        return regbench_names;                                                 \
    }                                                                          \
    NLOHMANN_JSON_SERIALIZE_ENUM(Enum, __VA_ARGS__)

}  // namespace regbench
