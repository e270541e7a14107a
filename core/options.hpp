#pragma once
// JSON binding for method options: defaults from the struct, unknown keys rejected by name.
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>

namespace regbench {

/// Parses `j` into Options (a struct with to_json/from_json, e.g. from
/// NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT). Keys absent from `j` keep the struct's
/// defaults. Throws std::invalid_argument naming `method` and the first unknown key or the
/// key whose value has the wrong type.
/// Throws std::invalid_argument naming `method` and the first key of `j` that `defaults` lacks
/// (listing the known keys) or whose JSON type differs from the default's (int and double
/// count as one type).
inline void CheckParamKeysAndTypes(const nlohmann::json& j,
                                   const nlohmann::json& defaults,
                                   const std::string& method) {
    for (const auto& item : j.items()) {
        if (!defaults.contains(item.key())) {
            std::string known;
            for (const auto& d : defaults.items()) known += (known.empty() ? "" : ", ") + d.key();
            throw std::invalid_argument(method + ": unknown parameter '" + item.key() +
                                        "' (known: " + known + ")");
        }
        const auto& def = defaults.at(item.key());
        const bool numeric_ok = def.is_number() && item.value().is_number();
        if (!numeric_ok && def.type() != item.value().type()) {
            throw std::invalid_argument(method + ": parameter '" + item.key() + "' expects " +
                                        def.type_name() + ", got " + item.value().dump());
        }
    }
}

/// Throws std::invalid_argument unless `j` is null or a JSON object.
inline void RequireParamObject(const nlohmann::json& j, const std::string& method) {
    if (!j.is_null() && !j.is_object()) {
        throw std::invalid_argument(method + ": parameters must be a JSON object, got " + j.dump());
    }
}

/// Parses `j` into Options (a struct with to_json/from_json, e.g. from
/// NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT). Keys absent from `j` keep the struct's
/// defaults. Throws std::invalid_argument naming `method` and the first unknown key or the
/// key whose value has the wrong type. Methods use MethodSpec (core/method_spec.hpp) instead.
template <class Options>
Options ParseOptions(const nlohmann::json& j, const std::string& method) {
    RequireParamObject(j, method);
    if (j.is_null()) return Options{};
    const nlohmann::json defaults = Options{};
    CheckParamKeysAndTypes(j, defaults, method);
    nlohmann::json merged = defaults;
    merged.update(j);
    try {
        return merged.get<Options>();
    } catch (const nlohmann::json::exception& e) {
        throw std::invalid_argument(method + ": bad parameters: " + e.what());
    }
}

/// Throws std::invalid_argument("<method>: parameter '<name>' ...") unless `ok`.
inline void Require(bool ok,
                    const std::string& method,
                    const std::string& name,
                    const std::string& why) {
    if (!ok) throw std::invalid_argument(method + ": parameter '" + name + "' " + why);
}

/// Throws std::invalid_argument("<method>: parameter '<name>' must be "a", "b" or "c", got "x"")
/// unless `value` is one of `allowed`.
inline void RequireOneOf(const std::string& value,
                         std::initializer_list<const char*> allowed,
                         const std::string& method,
                         const std::string& name) {
    std::string list;
    std::size_t i = 0;
    for (const char* a : allowed) {
        if (value == a) return;
        list += (i == 0 ? "" : (i + 1 == allowed.size() ? " or " : ", ")) + std::string("\"") + a +
                "\"";
        ++i;
    }
    Require(false, method, name, "must be " + list + ", got \"" + value + "\"");
}

}  // namespace regbench
