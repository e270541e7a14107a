#include "core/param_schema.hpp"

#include <cmath>
#include <cstdint>
#include <set>
#include <stdexcept>

#include "core/options.hpp"

namespace regbench {
namespace {

/// The comparison a range keyword stands for, and how its message writes it.
struct RangeRule {
    const char* keyword;
    const char* op;  ///< "" for x-finite
    bool (*ok)(double value, double bound);
};

constexpr RangeRule kRangeRules[] = {
    {"minimum", ">= ", [](double v, double b) { return v >= b; }},
    {"exclusiveMinimum", "> ", [](double v, double b) { return v > b; }},
    {"maximum", "<= ", [](double v, double b) { return v <= b; }},
    {"exclusiveMaximum", "< ", [](double v, double b) { return v < b; }},
    {"x-finite", "", [](double v, double) { return std::isfinite(v); }},
};

const RangeRule* FindRangeRule(const std::string& keyword) {
    for (const auto& rule : kRangeRules) {
        if (keyword == rule.keyword) return &rule;
    }
    return nullptr;
}

/// The same JSON as a key-sorted value (nlohmann has no conversion between its two kinds).
nlohmann::json Unordered(const nlohmann::ordered_json& j) {
    return nlohmann::json::parse(j.dump());
}

/// Whether `value` has the JSON type the schema's "type" names.
bool HasType(const nlohmann::json& value, const std::string& type) {
    if (type == "number") return value.is_number();
    if (type == "integer") return value.is_number_integer();
    if (type == "boolean") return value.is_boolean();
    if (type == "string") return value.is_string();
    if (type == "array") return value.is_array();
    return false;
}

}  // namespace

ParamSchema::ParamSchema(const char* text) {
    // ordered_json keeps the file's order of properties and of range keywords, which is the
    // order errors are reported in.
    nlohmann::ordered_json doc;
    try {
        doc = nlohmann::ordered_json::parse(text);
        document_ = Unordered(doc);
    } catch (const nlohmann::json::parse_error& e) {
        throw std::logic_error(std::string("parameter schema is not JSON: ") + e.what());
    }
    const std::string where = "parameter schema '" + doc.value("title", std::string("?")) + "'";
    auto fail = [&where](const std::string& why) { throw std::logic_error(where + ": " + why); };
    static const std::set<std::string> kTopKeys = {
        "$schema",         "title", "description", "type", "properties", "additionalProperties",
        "x-compat-presets"};
    for (const auto& item : doc.items()) {
        if (kTopKeys.count(item.key()) == 0) fail("unsupported keyword '" + item.key() + "'");
    }
    if (!doc.contains("title") || !doc["title"].is_string()) fail("needs a string \"title\"");
    if (!doc.contains("description") || !doc["description"].is_string()) {
        fail("needs a string \"description\"");
    }
    if (doc.value("type", std::string()) != "object") fail("\"type\" must be \"object\"");
    if (doc.value("additionalProperties", true) != false) {
        fail("\"additionalProperties\" must be false");
    }
    name_ = doc["title"].get<std::string>();
    summary_ = doc["description"].get<std::string>();
    defaults_ = nlohmann::json::object();
    const auto properties = doc.value("properties", nlohmann::ordered_json::object());
    if (!properties.is_object()) fail("\"properties\" must be an object");
    for (const auto& item : properties.items()) {
        const auto& p = item.value();
        Property prop;
        prop.key = item.key();
        const std::string at = "property '" + prop.key + "': ";
        // "type": "number", or ["number", "null"] for a key where null means "the default".
        const nlohmann::ordered_json type = p.value("type", nlohmann::ordered_json());
        const bool nullable =
            type.is_array() && type.size() == 2 && type[0].is_string() && type[1] == "null";
        if (!type.is_string() && !nullable) {
            fail(at + "needs a \"type\": a name, or [name, \"null\"]");
        }
        if (!p.contains("description") || !p["description"].is_string()) {
            fail(at + "needs a string \"description\"");
        }
        if (!p.contains("default")) fail(at + "needs a \"default\"");
        prop.type = (nullable ? type[0] : type).get<std::string>();
        prop.nullable = nullable;
        prop.doc = p["description"].get<std::string>();
        const nlohmann::json def = Unordered(p["default"]);
        if (!HasType(def, prop.type)) fail(at + "default does not have type " + prop.type);
        for (const auto& kw : p.items()) {
            const std::string& k = kw.key();
            if (k == "type" || k == "description" || k == "default") continue;
            if (k == "enum") {
                if (prop.type != "string" || !kw.value().is_array()) {
                    fail(at + "\"enum\" needs type string and a list");
                }
                for (const auto& c : kw.value()) {
                    if (!c.is_string()) fail(at + "\"enum\" entries must be strings");
                    prop.choices.push_back(c.get<std::string>());
                }
                prop.has_choices = true;
                continue;
            }
            if (FindRangeRule(k) == nullptr) fail(at + "unsupported keyword '" + k + "'");
            if (prop.type != "number" && prop.type != "integer") {
                fail(at + "'" + k + "' needs a numeric type");
            }
            if (k == "x-finite" ? kw.value() != true : !kw.value().is_number()) {
                fail(at + "'" + k + "' needs " + (k == "x-finite" ? "true" : "a number"));
            }
            prop.checks.emplace_back(k, Unordered(kw.value()));
        }
        if (prop.has_choices) {
            bool found = false;
            for (const auto& c : prop.choices) found = found || def == c;
            if (!found) fail(at + "default is not one of \"enum\"");
        }
        defaults_[prop.key] = def;
        properties_.push_back(std::move(prop));
    }
    if (doc.contains("x-compat-presets")) {
        const auto& presets = doc["x-compat-presets"];
        if (!presets.is_object() || !defaults_.contains("compat")) {
            fail("\"x-compat-presets\" needs an object and a \"compat\" property");
        }
        for (const auto& preset : presets.items()) {
            const nlohmann::json values = Unordered(preset.value());
            if (!values.is_object()) fail("compat preset '" + preset.key() + "' must be an object");
            try {
                CheckParamKeysAndTypes(values, defaults_, name_);
            } catch (const std::invalid_argument& e) {
                fail("compat preset '" + preset.key() + "': " + e.what());
            }
            compat_presets_[preset.key()] = values;
        }
    }
}

std::map<std::string, std::string> ParamSchema::Docs() const {
    std::map<std::string, std::string> docs;
    for (const auto& p : properties_) docs[p.key] = p.doc;
    return docs;
}

std::string ParamSchema::ValueType(const std::string& key) const {
    for (const auto& p : properties_) {
        if (p.key == key) return p.type;
    }
    return "";
}

const std::vector<std::string>* ParamSchema::Choices(const std::string& key) const {
    for (const auto& p : properties_) {
        if (p.key == key) return p.has_choices ? &p.choices : nullptr;
    }
    return nullptr;
}

std::vector<std::string> ParamSchema::Keys() const {
    std::vector<std::string> keys;
    for (const auto& p : properties_) keys.push_back(p.key);
    return keys;
}

nlohmann::json ParamSchema::Complete(const nlohmann::json& user) const {
    RequireParamObject(user, name_);
    nlohmann::json j = user.is_null() ? nlohmann::json::object() : user;
    for (const auto& p : properties_) {
        if (p.nullable && j.contains(p.key) && j.at(p.key).is_null()) j.erase(p.key);
    }
    CheckParamKeysAndTypes(j, defaults_, name_);
    nlohmann::json merged = defaults_;
    if (!compat_presets_.empty()) {
        const nlohmann::json& compat =
            j.contains("compat") ? j.at("compat") : defaults_.at("compat");
        const auto preset = compat.is_string() ? compat_presets_.find(compat.get<std::string>())
                                               : compat_presets_.end();
        if (preset != compat_presets_.end()) merged.update(preset->second);
    }
    merged.update(j);
    // Whole numbers for "integer" keys: the type check above lets any number through (an int
    // default accepts 2.0), and reading 2.5 into an int would silently truncate it to 2. JSON
    // Schema counts 2.0 as an integer, so only a fractional part (or inf/NaN) is refused.
    for (const auto& p : properties_) {
        const nlohmann::json& value = merged.at(p.key);
        if (p.type != "integer" || !value.is_number_float()) continue;
        const double v = value.get<double>();
        // Beyond 2^53 a float is no whole number one can name exactly, and 1e23 wrapped to
        // -2147483648 in an int member, which the range check then reported as the value.
        if (!std::isfinite(v) || std::trunc(v) != v || std::abs(v) > 9007199254740992.0) {
            throw std::invalid_argument(name_ + ": parameter '" + p.key +
                                        "' must be a whole number (|x| <= 2^53), got " +
                                        value.dump());
        }
    }
    // Strict choices: nlohmann's enum conversion alone would fall back to the first name.
    for (const auto& p : properties_) {
        if (!p.has_choices) continue;
        const nlohmann::json& value = merged.at(p.key);
        std::string list;
        bool found = false;
        for (const auto& c : p.choices) {
            found = found || value == c;
            list += (list.empty() ? "\"" : ", \"") + c + "\"";
        }
        if (!found) {
            throw std::invalid_argument(name_ + ": parameter '" + p.key + "' must be one of " +
                                        list + ", got " + value.dump());
        }
    }
    return merged;
}

void ParamSchema::CheckRanges(const nlohmann::json& values) const {
    for (const auto& p : properties_) {
        const nlohmann::json& value = values.at(p.key);
        for (const auto& [keyword, bound] : p.checks) {
            const RangeRule& rule = *FindRangeRule(keyword);
            const double bound_value = bound.is_number() ? bound.get<double>() : 0.0;
            if (rule.ok(value.get<double>(), bound_value)) continue;
            // The bound is written in the member's type, as the value is: ">= 1" for an
            // int, ">= 0.0" for a double.
            const std::string bound_text =
                keyword == "x-finite" ? "finite"
                                      : rule.op + (value.is_number_integer()
                                                       ? nlohmann::json(bound.get<std::int64_t>())
                                                       : nlohmann::json(bound.get<double>()))
                                                      .dump();
            throw std::invalid_argument(name_ + ": parameter '" + p.key + "' must be " +
                                        bound_text + ", got " + value.dump());
        }
    }
}

}  // namespace regbench
