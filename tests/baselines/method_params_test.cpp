// Every registered method's parameters, classical and learned, through the one system of
// core/params.hpp: the JSON Schema that `regbench methods --json` prints (generated from the
// options struct's Fields and Validate) against what creating the method accepts and records.
// The expected values come from the printed schema, the observed ones from parsing, so a
// schema that documents a default, range or choice the parser does not enforce fails here.
// The integer rule (2.0 accepted, 2.5 refused) is tested once here, for every method, and so
// is the rule that a parameter's range is stated once: printed from Validate, never in prose.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <regex>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "runners/registry.hpp"

namespace regbench {
namespace {

std::vector<std::string> SchemaMethodNames() {
    std::vector<std::string> names;
    for (const auto& m : AllMethods()) {
        if (!m.schema.is_null()) names.push_back(m.name);
    }
    return names;
}

/// The message of the std::invalid_argument that creating `method` with `params` throws,
/// or "" when it is accepted.
std::string Rejection(const MethodInfo& method, const nlohmann::json& params) {
    try {
        method.create(params);
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "";
}

bool Contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

/// A property's value type: "type" is a name, or [name, "null"] when null means the default.
std::string TypeOf(const nlohmann::json& property) {
    const nlohmann::json& type = property.at("type");
    return type.is_array() ? type.at(0).get<std::string>() : type.get<std::string>();
}

/// The range keywords of a schema property, bounds as doubles.
nlohmann::json RangeKeywords(const nlohmann::json& property) {
    nlohmann::json k = nlohmann::json::object();
    for (const char* keyword : {"minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"}) {
        if (property.contains(keyword)) k[keyword] = property.at(keyword).get<double>();
    }
    if (property.value("x-finite", false)) k["x-finite"] = true;
    return k;
}

/// A printed range (">= 1", "(0, 1]", ">= 0, finite", "finite") read back into the keywords
/// it stands for: the inverse of the printing, so the test does not format it a second time.
nlohmann::json ReadRange(std::string range) {
    nlohmann::json k = nlohmann::json::object();
    const std::string finite = "finite";
    if (range.size() >= finite.size() &&
        range.compare(range.size() - finite.size(), finite.size(), finite) == 0) {
        k["x-finite"] = true;
        range.erase(range.size() - finite.size());
        if (range.empty()) return k;
        if (range.size() < 2 || range.compare(range.size() - 2, 2, ", ") != 0) return "bad";
        range.erase(range.size() - 2);
    }
    const auto comma = range.find(", ");
    if (!range.empty() && (range.front() == '[' || range.front() == '(') &&
        comma != std::string::npos) {
        k[range.front() == '[' ? "minimum" : "exclusiveMinimum"] =
            std::stod(range.substr(1, comma - 1));
        k[range.back() == ']' ? "maximum" : "exclusiveMaximum"] =
            std::stod(range.substr(comma + 2, range.size() - comma - 3));
        return k;
    }
    for (const auto& [op, keyword] :
         std::vector<std::pair<std::string, std::string>>{{">= ", "minimum"},
                                                          {"> ", "exclusiveMinimum"},
                                                          {"<= ", "maximum"},
                                                          {"< ", "exclusiveMaximum"}}) {
        if (range.rfind(op, 0) == 0) {
            k[keyword] = std::stod(range.substr(op.size()));
            return k;
        }
    }
    return "bad";
}

/// The first range a one-line meaning states in words, or "": a comparison with a number
/// ("(> 0)", ">= 1"), an interval of numbers ("in (0, 1]", "[0, 1)"), "positive",
/// "non-negative". Comparisons with names or expressions ("|q - q_prev| < tol", ">= this",
/// "r < 1/4 of the target bbox diagonal") are meanings.
/// Checked on the keys that can have a range (numbers and integers): a choice's doc may
/// describe its rule with numbers (scale_rule: "when outside [0.5, 2]").
std::string RangeInProse(const std::string& meaning) {
    static const std::regex kRange(
        R"((^|[\s(;,])(>=|<=|>|<)\s*[-+]?[0-9.][0-9.e+-]*(?![/0-9a-zA-Z]))"
        R"(|[\[(]\s*[-+]?[0-9][0-9.e+-]*\s*,\s*[-+]?[0-9][0-9.e+-]*\s*[\])])"
        R"(|\b(positive|non-?negative)\b)",
        std::regex::icase);
    std::smatch m;
    return std::regex_search(meaning, m, kRange) ? m.str() : "";
}

class MethodSchema : public ::testing::TestWithParam<std::string> {
protected:
    const MethodInfo& info() const { return FindMethod(GetParam()); }
    const nlohmann::json& properties() const { return info().schema.at("properties"); }
};

TEST(MethodSchemas, EveryMethodHasOne) {
    for (const auto& m : AllMethods()) EXPECT_TRUE(m.schema.is_object()) << m.name;
}

TEST_P(MethodSchema, HeaderMatchesTheRegistryEntry) {
    const nlohmann::json& s = info().schema;
    EXPECT_EQ(s.at("title"), info().name);
    EXPECT_EQ(s.at("description"), info().summary);
    EXPECT_EQ(s.at("type"), "object");
    EXPECT_EQ(s.at("additionalProperties"), false);
}

TEST_P(MethodSchema, PropertiesAreTheParamsOfADefaultInstance) {
    const nlohmann::json params = info().create({})->Params();
    std::set<std::string> schema_keys;
    for (const auto& item : properties().items()) schema_keys.insert(item.key());
    std::set<std::string> param_keys;
    for (const auto& item : params.items()) param_keys.insert(item.key());
    EXPECT_EQ(schema_keys, param_keys);
}

TEST_P(MethodSchema, DocsPrintTheRangeOfValidateAndTheProseStatesNone) {
    // Issue 40: the prose of cpd's sigma2 said "(> 0)" while Validate checks ">= 0".
    for (const auto& item : properties().items()) {
        const std::string& key = item.key();
        const nlohmann::json& p = item.value();
        const std::string meaning = p.at("description").get<std::string>();
        const std::string& doc = info().param_docs.at(key);
        const nlohmann::json keywords = RangeKeywords(p);
        if (keywords.empty()) {
            EXPECT_EQ(doc, meaning) << key;
        } else {
            const std::string head = meaning + "; range ";
            ASSERT_EQ(doc.rfind(head, 0), 0u) << key << ": " << doc;
            EXPECT_EQ(ReadRange(doc.substr(head.size())), keywords) << key << ": " << doc;
        }
        const std::string type = TypeOf(p);
        if (type != "number" && type != "integer") continue;
        const std::string range = RangeInProse(meaning);
        EXPECT_EQ(range, "") << info().name << " '" << key << "' states a range in prose: \""
                             << range << "\" in \"" << meaning << "\"";
    }
}

TEST_P(MethodSchema, DefaultsRoundTripThroughTheStruct) {
    const nlohmann::json params = info().create({})->Params();
    for (const auto& item : properties().items()) {
        const nlohmann::json& def = item.value().at("default");
        const nlohmann::json& got = params.at(item.key());
        EXPECT_EQ(got, def) << item.key();
        // The same JSON number kind too, so `regbench methods` prints 1.0 where it did.
        EXPECT_EQ(got.is_number_integer(), def.is_number_integer()) << item.key();
        EXPECT_EQ(info().defaults.at(item.key()), def) << item.key();
    }
}

TEST_P(MethodSchema, EveryChoiceRoundTripsAndOthersAreRejected) {
    for (const auto& item : properties().items()) {
        if (!item.value().contains("enum")) continue;
        const std::string& key = item.key();
        for (const auto& choice : item.value().at("enum")) {
            // A name the enum lacks would come back as its first name (nlohmann's fallback).
            EXPECT_EQ(info().create({{key, choice}})->Params().at(key), choice) << key;
        }
        const std::string why = Rejection(info(), {{key, "no-such-choice"}});
        EXPECT_TRUE(Contains(why, "'" + key + "' must be one of")) << key << ": " << why;
        for (const auto& choice : item.value().at("enum")) {
            EXPECT_TRUE(Contains(why, choice.dump())) << key << ": " << why;
        }
    }
}

TEST_P(MethodSchema, EveryRangeKeywordIsEnforced) {
    const double kInf = std::numeric_limits<double>::infinity();
    for (const auto& item : properties().items()) {
        const std::string& key = item.key();
        const nlohmann::json& p = item.value();
        const bool integer = TypeOf(p) == "integer";
        const std::string must = "'" + key + "' must be ";
        // Just outside each bound is rejected; on an inclusive bound is accepted.
        auto check = [&](const char* keyword, double towards, bool inclusive) {
            if (!p.contains(keyword)) return;
            const double bound = p.at(keyword).get<double>();
            const nlohmann::json on =
                integer ? nlohmann::json(static_cast<long long>(bound)) : nlohmann::json(bound);
            const nlohmann::json outside =
                integer ? nlohmann::json(static_cast<long long>(bound) + (towards > 0 ? 1 : -1))
                        : nlohmann::json(std::nextafter(bound, towards));
            const std::string why = Rejection(info(), {{key, outside}});
            EXPECT_TRUE(Contains(why, must)) << key << " = " << outside << ": " << why;
            const std::string on_bound = Rejection(info(), {{key, on}});
            if (inclusive) {
                EXPECT_EQ(on_bound, "") << key << " = " << on;
            } else {
                EXPECT_TRUE(Contains(on_bound, must)) << key << " = " << on << ": " << on_bound;
            }
        };
        check("minimum", -kInf, true);
        check("exclusiveMinimum", -kInf, false);
        check("maximum", kInf, true);
        check("exclusiveMaximum", kInf, false);
        if (p.value("x-finite", false)) {
            for (const double bad : {kInf, -kInf, std::nan("")}) {
                const std::string why = Rejection(info(), {{key, bad}});
                EXPECT_TRUE(Contains(why, must)) << key << " = " << bad << ": " << why;
            }
        }
    }
}

TEST_P(MethodSchema, WrongJsonTypesAndUnknownKeysAreRejectedByName) {
    for (const auto& item : properties().items()) {
        const std::string& key = item.key();
        const bool numeric = TypeOf(item.value()) == "number" || TypeOf(item.value()) == "integer";
        const nlohmann::json wrong = numeric ? nlohmann::json("1") : nlohmann::json(1);
        const std::string why = Rejection(info(), {{key, wrong}});
        EXPECT_TRUE(Contains(why, "'" + key + "' expects")) << key << ": " << why;
        EXPECT_EQ(why.rfind(info().name + ": ", 0), 0u) << why;
    }
    EXPECT_TRUE(Contains(Rejection(info(), {{"no_such_key", 1}}), "unknown parameter"));
    EXPECT_TRUE(Contains(Rejection(info(), nlohmann::json::array()), "must be a JSON object"));
}

TEST_P(MethodSchema, IntegerKeysRefuseFractionsAndAcceptWholeFloats) {
    // JSON Schema's "integer": 2.0 is one, 2.5 is not (it must not be truncated to 2).
    for (const auto& item : properties().items()) {
        if (TypeOf(item.value()) != "integer") continue;
        const std::string& key = item.key();
        const nlohmann::json def = item.value().at("default");
        const std::string why = Rejection(info(), {{key, def.get<double>() + 0.5}});
        EXPECT_TRUE(Contains(why, "'" + key + "' must be a whole number")) << key << ": " << why;
        const nlohmann::json as_float = def.get<double>();  // e.g. 30 -> 30.0
        EXPECT_EQ(Rejection(info(), {{key, as_float}}), "") << key;
        EXPECT_EQ(info().create({{key, as_float}})->Params().at(key), def) << key;
        // Issue 27: 1e23 wrapped to -2147483648 in an int member and was reported as that.
        // Expected: refused with the value given (1e30 is exact enough that nlohmann prints
        // it back as 1e+30), never a wrapped one.
        const std::string huge = Rejection(info(), {{key, 1e30}});
        EXPECT_TRUE(Contains(huge, "'" + key + "' must be a whole number")) << key << ": " << huge;
        EXPECT_TRUE(Contains(huge, "got 1e+30")) << key << ": " << huge;
    }
}

TEST_P(MethodSchema, NullMeansTheDefaultOnlyWhereTheTypeAllowsIt) {
    for (const auto& item : properties().items()) {
        const std::string& key = item.key();
        const std::string why = Rejection(info(), {{key, nullptr}});
        if (item.value().at("type").is_array()) {  // [type, "null"]
            EXPECT_EQ(why, "") << key;
            EXPECT_EQ(info().create({{key, nullptr}})->Params().at(key), item.value().at("default"))
                << key;
        } else {
            EXPECT_TRUE(Contains(why, "'" + key + "' expects")) << key << ": " << why;
        }
    }
}

TEST_P(MethodSchema, CompatPresetsSetTheirDefaultsAndExplicitKeysWin) {
    const nlohmann::json& s = info().schema;
    if (!s.contains("x-compat-presets")) return;
    for (const auto& preset : s.at("x-compat-presets").items()) {
        const nlohmann::json params = info().create({{"compat", preset.key()}})->Params();
        for (const auto& value : preset.value().items()) {
            EXPECT_EQ(params.at(value.key()), value.value()) << preset.key() << " " << value.key();
            const nlohmann::json def = properties().at(value.key()).at("default");
            const nlohmann::json explicit_default =
                info().create({{"compat", preset.key()}, {value.key(), def}})->Params();
            EXPECT_EQ(explicit_default.at(value.key()), def) << value.key();
        }
    }
}

/// "icp-pl" -> "icp_pl": gtest names allow only letters, digits and underscores.
std::string TestName(const ::testing::TestParamInfo<std::string>& info) {
    std::string name = info.param;
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
}

INSTANTIATE_TEST_SUITE_P(Registry, MethodSchema, ::testing::ValuesIn(SchemaMethodNames()),
                         TestName);

}  // namespace
}  // namespace regbench
