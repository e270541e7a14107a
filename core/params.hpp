#pragma once
// Method parameters, declared once. A method's options are a plain struct with a default and a
// `///<` doc (meaning and unit; never the range) on every field, and two members:
//
//   template <class F> void Fields(F&& f) { f("maxiter", maxiter, "maximum EM iterations"); }
//   void Validate(ParamCheck& c) const { c.AtLeast("maxiter", maxiter, 1); }
//
// Fields binds each field to its JSON key and the one-line meaning `regbench methods` prints;
// Validate gives ranges (AtLeast, Above, AtMost, Below, Finite) and checks across parameters
// (Require). From the two come parsing (ParseParams), the parameters a row records
// (ParamsToJson), the docs (ParamDocs: the meaning, then "; range ..." from Validate) and the
// JSON Schema of `regbench methods --json` (ParamSchemaOf): each range call writes its JSON
// Schema keyword there instead of checking, so the schema, the docs and the parser cannot
// disagree. A range is stated only in Validate, never in the prose. A struct with a `compat`
// field may add `void ApplyCompat()`, the defaults its compat value presets; keys the user
// gives always win.
// docs/adding-a-method.md walks through an example.
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/enum_names.hpp"
#include "core/registration.hpp"

namespace regbench {

/// The `compat` choice of the probabilistic baselines: the correct algorithm, or the
/// published probreg 0.3.7 behaviour (each method's ApplyCompat says what it presets).
enum class Compat { kNone, kProbreg };
REGBENCH_CHOICES(Compat, {{Compat::kNone, "none"}, {Compat::kProbreg, "probreg"}})

/// Passed as Fields' fourth argument for a key where a JSON null means "the default".
enum class Nullable { kNo, kYes };

/// The options of a method without parameters.
struct NoOptions {
    template <class F>
    void Fields(F&& /*f*/) {}
    void Validate(class ParamCheck& /*c*/) const {}
};

/// Throws std::invalid_argument "<method>: parameter '<name>' <why>" unless `ok`.
inline void Require(bool ok, const std::string& method, const std::string& name,
                    const std::string& why) {
    if (!ok) throw std::invalid_argument(method + ": parameter '" + name + "' " + why);
}

/// The one rule for integer keys, of every method and config: a JSON number that is whole
/// (2 or 2.0; JSON Schema counts both as integers) and within [lo, hi]; 2.5, inf and NaN are
/// refused, as are floats beyond 2^53, which name no whole number exactly.
inline void RequireWholeNumber(const nlohmann::json& value, const std::string& method,
                               const std::string& name, double lo = -9007199254740992.0,
                               double hi = 9007199254740992.0) {
    if (value.is_number_integer()) {
        const double v = value.is_number_unsigned()
                             ? static_cast<double>(value.get<std::uint64_t>())
                             : static_cast<double>(value.get<std::int64_t>());
        if (v >= lo && v <= hi) return;
    } else if (value.is_number_float()) {
        const double v = value.get<double>();
        constexpr double kExactLimit = 9007199254740992.0;  // 2^53
        if (std::isfinite(v) && std::trunc(v) == v && std::abs(v) <= kExactLimit && v >= lo &&
            v <= hi) {
            return;
        }
    }
    const bool unbounded = lo <= -9007199254740992.0 && hi >= 9007199254740992.0;
    Require(false, method, name,
            unbounded ? "must be a whole number (|x| <= 2^53), got " + value.dump()
                      : "must be a whole number in [" + std::to_string(std::llround(lo)) + ", " +
                            std::to_string(std::llround(hi)) + "], got " + value.dump());
}

/// The ranges and cross-parameter checks of Validate. Checking (the default): the first rule
/// that fails throws std::invalid_argument "<method>: parameter '<key>' must be >= 1, got 0".
/// Describing (given `properties`): each range rule writes its JSON Schema keyword into
/// properties[key] and nothing is checked.
class ParamCheck {
public:
    explicit ParamCheck(std::string method) : method_(std::move(method)) {}
    ParamCheck(std::string method, nlohmann::json& properties)
        : method_(std::move(method)), properties_(&properties) {}

    template <class T>
    void AtLeast(const char* key, T value, std::common_type_t<T> bound) {
        Rule(key, "minimum", ">= ", value >= bound, value, bound);
    }
    template <class T>
    void Above(const char* key, T value, std::common_type_t<T> bound) {
        Rule(key, "exclusiveMinimum", "> ", value > bound, value, bound);
    }
    template <class T>
    void AtMost(const char* key, T value, std::common_type_t<T> bound) {
        Rule(key, "maximum", "<= ", value <= bound, value, bound);
    }
    template <class T>
    void Below(const char* key, T value, std::common_type_t<T> bound) {
        Rule(key, "exclusiveMaximum", "< ", value < bound, value, bound);
    }
    /// Rejects NaN and infinities, which a one-sided bound lets through ("x-finite": true).
    void Finite(const char* key, double value) {
        if (properties_ != nullptr) {
            (*properties_)[key]["x-finite"] = true;
        } else if (!std::isfinite(value)) {
            regbench::Require(false, method_, key,
                              "must be finite, got " + nlohmann::json(value).dump());
        }
    }
    /// A check across parameters; not part of the schema.
    void Require(bool ok, const char* key, const std::string& why) {
        if (properties_ == nullptr) regbench::Require(ok, method_, key, why);
    }

private:
    template <class T>
    void Rule(const char* key, const char* keyword, const char* op, bool ok, T value, T bound) {
        if (properties_ != nullptr) {
            (*properties_)[key][keyword] = bound;
        } else if (!ok) {
            regbench::Require(false, method_, key,
                              "must be " + std::string(op) + nlohmann::json(bound).dump() +
                                  ", got " + nlohmann::json(value).dump());
        }
    }

    std::string method_;
    nlohmann::json* properties_ = nullptr;
};

namespace params_detail {

template <class T>
struct IsChoice : std::is_enum<T> {};

/// The JSON Schema "type" of a field of C++ type T.
template <class T>
const char* SchemaType() {
    if constexpr (std::is_same_v<T, bool>) return "boolean";
    if constexpr (std::is_integral_v<T>) return "integer";
    if constexpr (std::is_floating_point_v<T>) return "number";
    return "string";  // std::string and choice enums
}

/// The JSON of a field's value: an enum by its name.
template <class T>
nlohmann::json ValueJson(const T& value) {
    if constexpr (std::is_enum_v<T>) {
        for (const auto& n : ChoicesOf(value)) {
            if (n.value == value) return n.name;
        }
        throw std::logic_error("enum value without a name");
    } else {
        return value;
    }
}

template <class Enum>
std::string ChoiceList(const std::vector<EnumName<Enum>>& names) {
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "\"" : ", \"") + std::string(n.name) + "\"";
    return list;
}

/// Reads one given key into its field: the JSON type must match the field's (integer and
/// number count as one), integers follow RequireWholeNumber and the field type's range,
/// choices are strict.
template <class T>
void ReadField(const nlohmann::json& value, T& field, const std::string& method, const char* key) {
    const auto expect = [&](bool ok, const char* type) {
        Require(ok, method, key, std::string("expects ") + type + ", got " + value.dump());
    };
    if constexpr (std::is_same_v<T, bool>) {
        expect(value.is_boolean(), "boolean");
        field = value.get<bool>();
    } else if constexpr (std::is_integral_v<T>) {
        expect(value.is_number(), "number");
        RequireWholeNumber(value, method, key, static_cast<double>(std::numeric_limits<T>::min()),
                           static_cast<double>(std::numeric_limits<T>::max()));
        field = static_cast<T>(value.get<double>());
    } else if constexpr (std::is_floating_point_v<T>) {
        expect(value.is_number(), "number");
        field = value.get<T>();
    } else if constexpr (std::is_enum_v<T>) {
        expect(value.is_string(), "string");
        for (const auto& n : ChoicesOf(T{})) {
            if (value == n.name) {
                field = n.value;
                return;
            }
        }
        Require(false, method, key,
                "must be one of " + ChoiceList(ChoicesOf(T{})) + ", got " + value.dump());
    } else {
        expect(value.is_string(), "string");
        field = value.get<std::string>();
    }
}

/// A range bound as `regbench methods` prints it: whole numbers without ".0" (0, 1, 1e-06).
inline std::string BoundText(const nlohmann::json& bound) {
    if (bound.is_number_float()) {
        const double v = bound.get<double>();
        if (std::trunc(v) == v && std::abs(v) < 1e15) return std::to_string(std::llround(v));
    }
    return bound.dump();
}

/// "; range <r>" for a schema property with range keywords, "" without: <r> is ">= 1",
/// "> 0", "<= 1" or "< 1" for one bound, an interval "[0, 1)" or "(0, 1]" for two, and
/// ", finite" follows (alone: "finite") where "x-finite" is set.
inline std::string RangeText(const nlohmann::json& property) {
    const auto text = [&](const char* keyword) {
        return property.contains(keyword) ? BoundText(property.at(keyword)) : std::string();
    };
    const bool closed_lo = property.contains("minimum");
    const bool closed_hi = property.contains("maximum");
    const std::string lo = closed_lo ? text("minimum") : text("exclusiveMinimum");
    const std::string hi = closed_hi ? text("maximum") : text("exclusiveMaximum");
    std::string range;
    if (!lo.empty() && !hi.empty()) {
        range = (closed_lo ? "[" : "(") + lo + ", " + hi + (closed_hi ? "]" : ")");
    } else if (!lo.empty()) {
        range = (closed_lo ? ">= " : "> ") + lo;
    } else if (!hi.empty()) {
        range = (closed_hi ? "<= " : "< ") + hi;
    }
    if (property.value("x-finite", false)) range += range.empty() ? "finite" : ", finite";
    return range.empty() ? "" : "; range " + range;
}

template <class Options, class = void>
struct HasCompat : std::false_type {};
template <class Options>
struct HasCompat<Options, std::void_t<decltype(std::declval<Options&>().ApplyCompat())>>
    : std::true_type {};

/// Reads the keys `user` gives into `o`; unknown keys are refused listing the known ones.
template <class Options>
void ReadGiven(const std::string& method, const nlohmann::json& user, Options& o) {
    std::map<std::string, bool> known;
    o.Fields([&](const char* key, auto& /*field*/, const char* /*doc*/,
                 Nullable /*nullable*/ = Nullable::kNo) { known[key] = true; });
    for (const auto& item : user.items()) {
        if (known.count(item.key()) != 0) continue;
        std::string list;
        for (const auto& k : known) list += (list.empty() ? "" : ", ") + k.first;
        throw std::invalid_argument(method + ": unknown parameter '" + item.key() +
                                    "' (known: " + list + ")");
    }
    o.Fields(
        [&](const char* key, auto& field, const char* /*doc*/, Nullable nullable = Nullable::kNo) {
            const auto it = user.find(key);
            if (it == user.end() || (it->is_null() && nullable == Nullable::kYes)) return;
            ReadField(*it, field, method, key);
        });
}

}  // namespace params_detail

/// Parses a method's parameters: `user` is null or a JSON object; absent keys keep the
/// struct's defaults (after the compat preset, if any); then Validate runs. Throws
/// std::invalid_argument "<method>: ..." naming the key.
template <class Options>
Options ParseParams(const std::string& method, const nlohmann::json& user) {
    if (!user.is_null() && !user.is_object()) {
        throw std::invalid_argument(method + ": parameters must be a JSON object, got " +
                                    user.dump());
    }
    const nlohmann::json given = user.is_null() ? nlohmann::json::object() : user;
    Options o{};
    params_detail::ReadGiven(method, given, o);
    if constexpr (params_detail::HasCompat<Options>::value) {
        Options preset{};
        preset.compat = o.compat;
        preset.ApplyCompat();
        o = preset;
        params_detail::ReadGiven(method, given, o);
    }
    ParamCheck check(method);
    o.Validate(check);
    return o;
}

/// Every parameter as JSON (enums by name), as result rows record them.
template <class Options>
nlohmann::json ParamsToJson(Options o) {
    nlohmann::json j = nlohmann::json::object();
    o.Fields(
        [&](const char* key, auto& field, const char* /*doc*/,
            Nullable /*nullable*/ = Nullable::kNo) { j[key] = params_detail::ValueJson(field); });
    return j;
}

/// The describe pass of Fields and Validate: key -> its JSON Schema property ("type",
/// "description" (Fields' doc), "default", "enum" and the range keywords Validate declares).
template <class Options>
nlohmann::json ParamProperties(const std::string& name) {
    nlohmann::json properties = nlohmann::json::object();
    Options o{};
    o.Fields([&](const char* key, auto& field, const char* doc, Nullable nullable = Nullable::kNo) {
        using T = std::decay_t<decltype(field)>;
        nlohmann::json& p = properties[key];
        // Not `p["type"] = {p["type"], "null"}`: nlohmann 3.11.2 leaks the old string when an
        // initializer list reads the element it is assigned to (LeakSanitizer found it).
        const char* type = params_detail::SchemaType<T>();
        p["type"] = nullable == Nullable::kYes ? nlohmann::json::array({type, "null"})
                                               : nlohmann::json(type);
        p["description"] = doc;
        p["default"] = params_detail::ValueJson(field);
        if constexpr (std::is_enum_v<T>) {
            for (const auto& n : ChoicesOf(field)) p["enum"].push_back(n.name);
        }
    });
    ParamCheck describe(name, properties);
    o.Validate(describe);
    return properties;
}

/// key -> the line `regbench methods` prints: Fields' one-line meaning, then the range
/// Validate declares (params_detail::RangeText), e.g. "ICP iterations; range >= 1". The
/// prose never restates a range, so the two cannot disagree.
template <class Options>
std::map<std::string, std::string> ParamDocs() {
    std::map<std::string, std::string> docs;
    const nlohmann::json properties = ParamProperties<Options>("");
    for (const auto& item : properties.items()) {
        docs[item.key()] = item.value().at("description").get<std::string>() +
                           params_detail::RangeText(item.value());
    }
    return docs;
}

/// The JSON Schema (draft 2020-12) of the parameters: per key "type", "description",
/// "default", "enum" and the range keywords of Validate; "x-compat-presets" lists what each
/// compat value presets.
template <class Options>
nlohmann::json ParamSchemaOf(const std::string& name, const std::string& summary) {
    const nlohmann::json properties = ParamProperties<Options>(name);
    nlohmann::json schema = {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
                             {"title", name},
                             {"description", summary},
                             {"type", "object"},
                             {"additionalProperties", false},
                             {"properties", properties}};
    if constexpr (params_detail::HasCompat<Options>::value) {
        const Options o{};
        const nlohmann::json defaults = ParamsToJson(o);
        for (const auto& c : ChoicesOf(o.compat)) {
            Options preset{};
            preset.compat = c.value;
            preset.ApplyCompat();
            const nlohmann::json values = ParamsToJson(preset);
            nlohmann::json diff = nlohmann::json::object();
            for (const auto& item : values.items()) {
                if (item.key() != "compat" && item.value() != defaults.at(item.key())) {
                    diff[item.key()] = item.value();
                }
            }
            if (!diff.empty()) schema["x-compat-presets"][c.name] = diff;
        }
    }
    return schema;
}

/// Base of a method with parameters: Name() and Params() come from here.
template <class Options>
class ParamMethod : public RegistrationMethod {
public:
    ParamMethod(std::string name, Options options)
        : name_(std::move(name)), options_(std::move(options)) {}
    std::string Name() const override { return name_; }
    nlohmann::json Params() const override { return ParamsToJson(options_); }

protected:
    const Options& options() const { return options_; }

private:
    std::string name_;
    Options options_;
};

/// The algorithm of a method without per-instance state: options, clouds and context in,
/// result out (see RegistrationMethod::DoAlign for the contract).
template <class Options>
using AlignFunction = AlignResult (*)(const Options& options, const PointCloud& source,
                                      const PointCloud& target, const AlignContext& context);

/// A ParamMethod whose DoAlign calls an AlignFunction.
template <class Options>
class FunctionMethod final : public ParamMethod<Options> {
public:
    FunctionMethod(std::string name, Options options, AlignFunction<Options> align)
        : ParamMethod<Options>(std::move(name), std::move(options)), align_(align) {}

protected:
    AlignResult DoAlign(const PointCloud& source, const PointCloud& target,
                        const AlignContext& context) override {
        return align_(this->options(), source, target, context);
    }

private:
    AlignFunction<Options> align_;
};

/// MethodInfo without `create` and `cost`: name, summary, docs, defaults and schema.
template <class Options>
MethodInfo DescribeParams(const std::string& name, const std::string& summary) {
    MethodInfo info;
    info.name = name;
    info.summary = summary;
    info.param_docs = ParamDocs<Options>();
    info.defaults = ParamsToJson(Options{});
    info.schema = ParamSchemaOf<Options>(name, summary);
    return info;
}

/// MethodInfo without `create`: DescribeParams and the cost class. The options struct declares
/// its method's cost class as `CostClass Cost() const` (it may depend on the options: CPD's
/// dense E-step is quadratic, its default approximation is not).
template <class Options>
MethodInfo DescribeMethod(const std::string& name, const std::string& summary) {
    static_assert(std::is_same_v<decltype(std::declval<const Options&>().Cost()), CostClass>,
                  "a method's options struct declares `CostClass Cost() const`");
    MethodInfo info = DescribeParams<Options>(name, summary);
    info.cost = [name](const nlohmann::json& params) {
        return ParseParams<Options>(name, params).Cost();
    };
    return info;
}

/// The registry entry of a method given as a function.
template <class Options>
MethodInfo MakeMethodInfo(const std::string& name, const std::string& summary,
                          AlignFunction<Options> align) {
    MethodInfo info = DescribeMethod<Options>(name, summary);
    info.create = [name, align](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        return std::make_unique<FunctionMethod<Options>>(name, ParseParams<Options>(name, j),
                                                         align);
    };
    return info;
}

/// The registry entry of a method class `Method`, a ParamMethod<Options> constructible from
/// (name, Options): for methods that keep state or override AllowsScale.
template <class Method, class Options>
MethodInfo MakeMethodInfo(const std::string& name, const std::string& summary) {
    MethodInfo info = DescribeMethod<Options>(name, summary);
    info.create = [name](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        return std::make_unique<Method>(name, ParseParams<Options>(name, j));
    };
    return info;
}

/// Parses a config struct bound by NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT (model and
/// training configs, whose JSON is also a file format): keys absent from `j` keep the
/// struct's defaults; unknown keys, wrong JSON types, fractional values of integer keys
/// (RequireWholeNumber) and integers the field's type cannot hold throw std::invalid_argument
/// naming `what` and the key.
template <class Config>
Config ParseConfig(const nlohmann::json& j, const std::string& what) {
    if (!j.is_null() && !j.is_object()) {
        throw std::invalid_argument(what + ": parameters must be a JSON object, got " + j.dump());
    }
    nlohmann::json merged = Config{};
    if (j.is_null()) return Config{};
    nlohmann::json given = j;
    std::vector<std::string> integer_keys;
    for (const auto& item : j.items()) {
        const auto def = merged.find(item.key());
        if (def == merged.end()) {
            std::string known;
            for (const auto& d : merged.items()) known += (known.empty() ? "" : ", ") + d.key();
            throw std::invalid_argument(what + ": unknown parameter '" + item.key() +
                                        "' (known: " + known + ")");
        }
        const bool numeric_ok = def->is_number() && item.value().is_number();
        Require(numeric_ok || def->type() == item.value().type(), what, item.key(),
                std::string("expects ") + def->type_name() + ", got " + item.value().dump());
        if (def->is_number_integer()) {
            RequireWholeNumber(item.value(), what, item.key());
            integer_keys.push_back(item.key());
            // 2.0 as the integer 2 (exact: |x| <= 2^53), so that no float is cast to an int.
            if (item.value().is_number_float()) {
                given[item.key()] = static_cast<std::int64_t>(item.value().get<double>());
            }
        }
    }
    merged.update(given);
    Config c;
    try {
        c = merged.get<Config>();
    } catch (const nlohmann::json::exception& e) {
        throw std::invalid_argument(what + ": bad parameters: " + e.what());
    }
    // An integer its field's type cannot hold (3e9 in an int) comes back as another number;
    // compared as text, since nlohmann's == calls -1 and 2^64 - 1 equal.
    const nlohmann::json back = c;
    for (const auto& key : integer_keys) {
        Require(back.at(key).dump() == given.at(key).dump(), what, key,
                "is out of range of its integer type, got " + j.at(key).dump());
    }
    return c;
}

/// ParseConfig of a network family's config: an "arch" key, when present, must be `arch` and
/// is dropped first (zoo configs and checkpoints name their family); errors name "ARCH config".
template <class Config>
Config ParseNetworkConfig(const nlohmann::json& j, const std::string& arch) {
    nlohmann::json fields = j;
    if (j.is_object() && j.contains("arch")) {
        if (j.at("arch") != arch) {
            throw std::invalid_argument(arch + " config: arch is " + j.at("arch").dump());
        }
        fields.erase("arch");
    }
    return ParseConfig<Config>(fields, arch + " config");
}

}  // namespace regbench
