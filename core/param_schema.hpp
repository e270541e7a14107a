#pragma once
// A method's parameters as data: a JSON Schema (draft 2020-12) subset per method, e.g.
// baselines/icp.schema.json, compiled into the binary. The schema is the one source of each
// parameter's documentation, default, range and choices; `regbench methods --json` prints it,
// so editors can validate configs against the same text that the parser enforces.
//
// The subset: top-level "title" (registry name), "description" (one-line summary),
// "type": "object", "additionalProperties": false, "properties" and the custom
// "x-compat-presets" ({compat value: {key: default, ...}}). Each property has "type"
// ("number", "integer", "boolean", "string" or "array"; or [one of them, "null"], where a
// user's null means the default; "integer" refuses fractions), "description", "default", and
// optionally "minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum", "x-finite": true
// (rejects NaN and infinities, which a bound alone may let through) and "enum" (strings).
// Range keywords run in the order they are written, so the first failing one is reported.
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace regbench {

class ParamSchema {
public:
    /// Parses and checks `text`; throws std::logic_error naming the problem (a malformed
    /// schema is a programming error, caught by any test that lists the methods).
    explicit ParamSchema(const char* text);

    const std::string& name() const { return name_; }        ///< "title"
    const std::string& summary() const { return summary_; }  ///< "description"
    const nlohmann::json& document() const { return document_; }
    /// key -> "default", as a (key-sorted) JSON object.
    const nlohmann::json& defaults() const { return defaults_; }
    /// key -> "description".
    std::map<std::string, std::string> Docs() const;
    /// The "enum" of `key`, or nullptr when it has none.
    const std::vector<std::string>* Choices(const std::string& key) const;
    /// The value type of `key` ("number", "integer", ...; without a "null" alternative); ""
    /// when the schema has no such key.
    std::string ValueType(const std::string& key) const;
    /// Property keys in the order the schema lists them.
    std::vector<std::string> Keys() const;

    /// The first half of parsing, on JSON alone: `user` must be null or an object whose keys
    /// are properties and whose values have the property's JSON type (integer and number
    /// count as one); absent keys take the compat preset's value (when the "compat" value
    /// names one), then the default; string choices must be in "enum". Returns the complete
    /// parameter object. Throws std::invalid_argument "<name>: ..." naming the key.
    nlohmann::json Complete(const nlohmann::json& user) const;

    /// Range keywords against `values` (every key, as the options struct writes them);
    /// throws std::invalid_argument "<name>: parameter '<key>' must be >= 1, got 0".
    void CheckRanges(const nlohmann::json& values) const;

private:
    struct Property {
        std::string key;
        std::string type;
        bool nullable = false;  ///< "type": [type, "null"]: a null value means the default
        std::string doc;
        /// Range keywords in schema order: ("minimum", 0.0), ("x-finite", true), ...
        std::vector<std::pair<std::string, nlohmann::json>> checks;
        std::vector<std::string> choices;  ///< empty unless "enum"
        bool has_choices = false;
    };

    std::string name_;
    std::string summary_;
    nlohmann::json document_;
    nlohmann::json defaults_;
    std::vector<Property> properties_;
    std::map<std::string, nlohmann::json> compat_presets_;
};

}  // namespace regbench
