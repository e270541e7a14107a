#pragma once
// Method boilerplate written once. A method declares its options struct and one table
// (MethodSpec) that binds each JSON key to a struct member and documents it; from that table
// come the struct's JSON reading and writing, the `methods` listing (MethodInfo::param_docs),
// compat presets and the `create` function. docs/adding-a-method.md walks through an example.
#include <cmath>
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
#include "core/registration.hpp"

namespace regbench {

/// The `compat` choice of the probabilistic baselines: the correct algorithm, or the
/// published probreg 0.3.7 behaviour (its presets are each method's compat_presets).
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

/// One documented parameter: its JSON key, how to write, read and check it, and its meaning.
template <class Options>
struct ParamSpec {
    std::string key;
    std::string doc;  ///< one line: units, range, why this default
    std::function<void(const Options&, nlohmann::json&)> write;
    /// Reads j[key] into the struct; throws std::invalid_argument naming method and key.
    std::function<void(const nlohmann::json&, Options&, const std::string& method)> read;
    /// Range checks, run after parsing; each throws std::invalid_argument naming the key.
    std::vector<std::function<void(const Options&, const std::string& method)>> checks;
};

/// A ParamSpec under construction that still knows the member's type, so range checks can be
/// chained onto it: Param("tol", &O::tol, "...").AtLeast(0.0).Finite().
template <class Options, class T>
class TypedParam {
public:
    TypedParam(const char* key, T Options::*member, const char* doc);
    operator ParamSpec<Options>() const { return spec_; }  // NOLINT: table entries convert

    TypedParam& Greater(T bound) {
        return Check([=](T v) { return v > bound; }, "> ", bound);
    }
    TypedParam& AtLeast(T bound) {
        return Check([=](T v) { return v >= bound; }, ">= ", bound);
    }
    TypedParam& Below(T bound) {
        return Check([=](T v) { return v < bound; }, "< ", bound);
    }
    TypedParam& AtMost(T bound) {
        return Check([=](T v) { return v <= bound; }, "<= ", bound);
    }
    /// Rejects NaN and infinities (a comparison alone lets +inf through).
    TypedParam& Finite() {
        return Check([](T v) { return std::isfinite(static_cast<double>(v)); }, "finite", T{});
    }

private:
    template <class Pred>
    TypedParam& Check(Pred ok, const char* what, T bound) {
        const std::string key = spec_.key;
        const std::string rule =
            std::string(what) + (std::string(what) == "finite" ? "" : nlohmann::json(bound).dump());
        T Options::*member = member_;
        spec_.checks.push_back([=](const Options& o, const std::string& method) {
            if (!ok(o.*member)) {
                throw std::invalid_argument(method + ": parameter '" + key + "' must be " + rule +
                                            ", got " + nlohmann::json(o.*member).dump());
            }
        });
        return *this;
    }

    T Options::*member_;
    ParamSpec<Options> spec_;
};

/// Binds `member` to `key`. Enum-class members are read strictly: a string that is not one
/// of the enum's names is an error listing the choices (nlohmann alone would fall back to
/// the first value).
template <class Options, class T>
TypedParam<Options, T> Param(const char* key, T Options::*member, const char* doc) {
    return TypedParam<Options, T>(key, member, doc);
}

template <class Options, class T>
TypedParam<Options, T>::TypedParam(const char* key, T Options::*member, const char* doc)
    : member_(member) {
    spec_.key = key;
    spec_.doc = doc;
    spec_.write = [key, member](const Options& o, nlohmann::json& j) { j[key] = o.*member; };
    spec_.read = [key, member](const nlohmann::json& j, Options& o, const std::string& method) {
        const nlohmann::json& value = j.at(key);
        if constexpr (std::is_enum_v<T>) {
            std::string list;
            for (const std::string& name : EnumChoices<T>()) {
                if (value == name) {
                    o.*member = value.template get<T>();
                    return;
                }
                list += (list.empty() ? "\"" : ", \"") + name + "\"";
            }
            throw std::invalid_argument(method + ": parameter '" + key + "' must be one of " +
                                        list + ", got " + value.dump());
        } else {
            o.*member = value.template get<T>();
        }
    };
}

/// Everything about a method that is not its algorithm.
template <class Options>
struct MethodSpec {
    std::string name;     ///< registry name
    std::string summary;  ///< one line for `regbench methods`
    std::vector<ParamSpec<Options>> params;
    /// Checks across parameters beyond each Param's own range checks (may be empty);
    /// throws std::invalid_argument (core/options.hpp Require).
    std::function<void(const Options&)> validate;
    /// Compat presets as data: the value of the "compat" key -> defaults it sets for keys the
    /// user did not give. Empty for methods without compat modes.
    std::map<std::string, nlohmann::json> compat_presets;

    nlohmann::json ToJson(const Options& o) const {
        nlohmann::json j = nlohmann::json::object();
        for (const auto& p : params) p.write(o, j);
        return j;
    }

    /// Parses user parameters: unknown keys and wrong JSON types are rejected by name, absent
    /// keys take the compat preset's value (if any), then the struct's default; then every
    /// parameter's range checks and validate() run.
    Options Parse(const nlohmann::json& user) const {
        RequireParamObject(user, name);
        const nlohmann::json j = user.is_null() ? nlohmann::json::object() : user;
        const nlohmann::json defaults = ToJson(Options{});
        CheckParamKeysAndTypes(j, defaults, name);
        nlohmann::json merged = defaults;
        if (!compat_presets.empty()) {
            const nlohmann::json compat =
                j.contains("compat") ? j.at("compat") : defaults.at("compat");
            const auto preset = compat.is_string() ? compat_presets.find(compat.get<std::string>())
                                                   : compat_presets.end();
            if (preset != compat_presets.end()) merged.update(preset->second);
        }
        merged.update(j);
        Options o;
        for (const auto& p : params) {
            try {
                p.read(merged, o, name);
            } catch (const nlohmann::json::exception& e) {
                throw std::invalid_argument(name + ": bad parameter '" + p.key + "': " + e.what());
            }
        }
        for (const auto& p : params) {
            for (const auto& check : p.checks) check(o, name);
        }
        if (validate) validate(o);
        return o;
    }

    std::map<std::string, std::string> Docs() const {
        std::map<std::string, std::string> docs;
        for (const auto& p : params) docs[p.key] = p.doc;
        return docs;
    }
};

/// MethodInfo without `create`: name, summary, docs and defaults from the table.
template <class Options>
MethodInfo DescribeMethod(const MethodSpec<Options>& spec) {
    MethodInfo info;
    info.name = spec.name;
    info.summary = spec.summary;
    info.param_docs = spec.Docs();
    info.defaults = spec.ToJson(Options{});
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
