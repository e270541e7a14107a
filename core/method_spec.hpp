#pragma once
// Method boilerplate written once. A method declares its options struct (C++ types only, bound
// to JSON by REGBENCH_OPTION_FIELDS) and its parameter schema (baselines/<method>.schema.json:
// docs, defaults, ranges, choices, compat presets; core/param_schema.hpp); a MethodSpec joins
// the two, and from it come parsing, the `methods` listing (MethodInfo::param_docs, defaults,
// schema) and the `create` function. docs/adding-a-method.md walks through an example.
#include <algorithm>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/options.hpp"
#include "core/param_schema.hpp"
#include "core/registration.hpp"

namespace regbench {

/// The `compat` choice of the probabilistic baselines: the correct algorithm, or the
/// published probreg 0.3.7 behaviour (its presets are each schema's "x-compat-presets").
enum class Compat { kNone, kProbreg };
NLOHMANN_JSON_SERIALIZE_ENUM(Compat, {{Compat::kNone, "none"}, {Compat::kProbreg, "probreg"}})

/// The JSON names of an enum class serialised with NLOHMANN_JSON_SERIALIZE_ENUM, in value
/// order. The macro keeps its table private, so the names are read back by serialising the
/// values 0, 1, ... until one maps to the first name again (the macro's fallback); enums used
/// as choices therefore number their values 0..n-1, which enum classes do by default.
template <class Enum>
std::vector<std::string> EnumChoices() {
    std::vector<std::string> names;
    constexpr int kMaxChoices = 64;
    for (int v = 0; v < kMaxChoices; ++v) {
        const std::string name = nlohmann::json(static_cast<Enum>(v)).template get<std::string>();
        if (v > 0 && name == names.front()) break;
        names.push_back(name);
    }
    return names;
}

/// Binds an options struct's members to JSON, one line per struct, after the struct:
///   REGBENCH_OPTION_FIELDS(IcpOptions, max_correspondence_distance, max_iterations, ...)
/// It defines nlohmann's to_json/from_json (NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE) and
/// VisitOptionFields(options, visitor), which calls visitor("member", options.member) per
/// member with its C++ type, so MethodSpec can read each key on its own (errors name it) and
/// check the struct against the schema (same keys, JSON types and enum names). The struct
/// itself holds no defaults: they are the schema's.
#define REGBENCH_OPTION_FIELDS(Type, ...)                                                   \
    NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(Type, __VA_ARGS__)                                   \
    template <class RegbenchVisitor>                                                        \
    [[maybe_unused]] void VisitOptionFields(Type& regbench_options,                         \
                                            RegbenchVisitor&& regbench_visitor) {           \
        NLOHMANN_JSON_EXPAND(NLOHMANN_JSON_PASTE(REGBENCH_VISIT_OPTION_FIELD, __VA_ARGS__)) \
    }
#define REGBENCH_VISIT_OPTION_FIELD(member) regbench_visitor(#member, regbench_options.member);

/// The options of a method without parameters (its schema has no properties).
struct NoOptions {};
inline void to_json(nlohmann::json& j, const NoOptions& /*o*/) { j = nlohmann::json::object(); }
inline void from_json(const nlohmann::json& /*j*/, NoOptions& /*o*/) {}
template <class Visitor>
void VisitOptionFields(NoOptions& /*o*/, Visitor&& /*visitor*/) {}

/// The schema "type" a member of C++ type T has.
template <class T>
const char* SchemaTypeOf() {
    if constexpr (std::is_same_v<T, bool>) {
        return "boolean";
    } else if constexpr (std::is_integral_v<T>) {
        return "integer";
    } else if constexpr (std::is_floating_point_v<T>) {
        return "number";
    } else if constexpr (std::is_enum_v<T> || std::is_same_v<T, std::string>) {
        return "string";
    } else {
        return "array";
    }
}

/// Everything about a method that is not its algorithm: its parameter schema
/// (core/param_schema.hpp, one baselines/<method>.schema.json each) bound to an options
/// struct, plus the checks across parameters that a schema cannot express.
template <class Options>
struct MethodSpec {
    /// `schema_text`: the method's JSON schema (baselines/schemas.hpp BaselineSchema, or a
    /// literal). `validate`: checks across parameters beyond each key's own range (may be
    /// null); throws std::invalid_argument (core/options.hpp Require). Throws
    /// std::logic_error when the schema and the struct disagree (keys, types, enum names).
    explicit MethodSpec(const char* schema_text,
                        std::function<void(const Options&)> validate_fn = nullptr)
        : schema(schema_text),
          name(schema.name()),
          summary(schema.summary()),
          validate(std::move(validate_fn)) {
        CheckAgainstStruct();
    }

    ParamSchema schema;
    std::string name;     ///< registry name: the schema's "title"
    std::string summary;  ///< one line for `regbench methods`: the schema's "description"
    std::function<void(const Options&)> validate;

    nlohmann::json ToJson(const Options& o) const { return o; }

    /// Parses user parameters: unknown keys and wrong JSON types are rejected by name, absent
    /// keys take the compat preset's value (if any), then the schema's default; choices are
    /// strict; then every range keyword and validate() run.
    Options Parse(const nlohmann::json& user) const {
        Options o = Read(schema.Complete(user));
        schema.CheckRanges(ToJson(o));
        if (validate) validate(o);
        return o;
    }

    /// The schema's defaults in the struct (no checks).
    Options Defaults() const { return Read(schema.defaults()); }

    std::map<std::string, std::string> Docs() const { return schema.Docs(); }

private:
    Options Read(const nlohmann::json& values) const {
        Options o{};
        VisitOptionFields(o, [&](const char* key, auto& member) {
            using T = std::decay_t<decltype(member)>;
            try {
                member = values.at(key).template get<T>();
            } catch (const nlohmann::json::exception& e) {
                throw std::invalid_argument(name + ": bad parameter '" + key + "': " + e.what());
            }
        });
        return o;
    }

    void CheckAgainstStruct() const {
        const std::vector<std::string> keys = schema.Keys();
        std::vector<std::string> members;
        auto fail = [this](const std::string& key, const std::string& why) {
            throw std::logic_error("parameter schema '" + name + "': property '" + key + "' " +
                                   why);
        };
        Options o{};
        VisitOptionFields(o, [&](const char* key, auto& member) {
            using T = std::decay_t<decltype(member)>;
            members.push_back(key);
            if (std::find(keys.begin(), keys.end(), key) == keys.end()) {
                fail(key, "is missing (it is a member of the options struct)");
            }
            const std::string type = schema.ValueType(key);
            if (type != SchemaTypeOf<T>()) {
                fail(key, "has type " + type + " but the member is " + SchemaTypeOf<T>());
            }
            const std::vector<std::string>* choices = schema.Choices(key);
            if constexpr (std::is_enum_v<T>) {
                if (choices == nullptr || *choices != EnumChoices<T>()) {
                    fail(key, "needs \"enum\": the enum's names in value order");
                }
            } else if (choices != nullptr) {
                fail(key, "has \"enum\" but the member is not an enum class");
            }
        });
        for (const auto& key : keys) {
            if (std::find(members.begin(), members.end(), key) == members.end()) {
                fail(key, "is not a member of the options struct");
            }
        }
    }
};

/// The MethodSpec of `Options`, built from `schema_text` (and `validate`) on the first call and
/// kept for the program's life (instances refer to it): a function-local static per options
/// struct, so each method's struct must be its own type.
template <class Options>
const MethodSpec<Options>& SpecOf(const char* schema_text,
                                  std::function<void(const Options&)> validate = nullptr) {
    static const MethodSpec<Options> spec(schema_text, std::move(validate));
    return spec;
}

/// MethodInfo without `create`: name, summary, docs, defaults and schema from the spec.
template <class Options>
MethodInfo DescribeMethod(const MethodSpec<Options>& spec) {
    MethodInfo info;
    info.name = spec.name;
    info.summary = spec.summary;
    info.param_docs = spec.Docs();
    info.defaults = spec.ToJson(spec.Defaults());
    info.schema = spec.schema.document();
    return info;
}

/// Base class of a method built from a MethodSpec: Name() and Params() come from the spec.
template <class Options>
class SpecMethod : public RegistrationMethod {
public:
    SpecMethod(const MethodSpec<Options>& spec, Options options)
        : spec_(spec), options_(std::move(options)) {}
    std::string Name() const override { return spec_.name; }
    nlohmann::json Params() const override { return spec_.ToJson(options_); }

protected:
    const Options& options() const { return options_; }

private:
    const MethodSpec<Options>& spec_;  ///< a function-local static of the method's file
    Options options_;
};

/// The algorithm of a method without per-instance state: options, clouds and context in,
/// result out (see RegistrationMethod::DoAlign for the contract).
template <class Options>
using AlignFunction = AlignResult (*)(const Options& options,
                                      const PointCloud& source,
                                      const PointCloud& target,
                                      const AlignContext& context);

/// A SpecMethod whose DoAlign calls an AlignFunction.
template <class Options>
class FunctionMethod final : public SpecMethod<Options> {
public:
    FunctionMethod(const MethodSpec<Options>& spec, Options options, AlignFunction<Options> align)
        : SpecMethod<Options>(spec, std::move(options)), align_(align) {}

protected:
    AlignResult DoAlign(const PointCloud& source,
                        const PointCloud& target,
                        const AlignContext& context) override {
        return align_(this->options(), source, target, context);
    }

private:
    AlignFunction<Options> align_;
};

/// The registry entry of a method given as a function. `spec` must outlive every instance:
/// pass a function-local static.
template <class Options>
MethodInfo MakeMethodInfo(const MethodSpec<Options>& spec, AlignFunction<Options> align) {
    MethodInfo info = DescribeMethod(spec);
    info.create = [&spec, align](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        return std::make_unique<FunctionMethod<Options>>(spec, spec.Parse(j), align);
    };
    return info;
}

/// The registry entry of a method class `Method` (constructible from (const MethodSpec&,
/// Options); for methods that keep state or override AllowsScale). `spec` must outlive every
/// instance: pass a function-local static.
template <class Method, class Options>
MethodInfo MakeMethodInfo(const MethodSpec<Options>& spec) {
    MethodInfo info = DescribeMethod(spec);
    info.create = [&spec](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        return std::make_unique<Method>(spec, spec.Parse(j));
    };
    return info;
}

}  // namespace regbench
