#include "networks/checkpoint/authors_checkpoint.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "networks/checkpoint/authors_format.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/family.hpp"
#include "networks/net.hpp"
#include "networks/zoo.hpp"

namespace regbench::networks {
namespace fs = std::filesystem;
namespace {

std::string ShapeString(c10::IntArrayRef s) {
    std::ostringstream os;
    os << "[";
    for (size_t j = 0; j < s.size(); ++j) os << (j ? ", " : "") << s[j];
    os << "]";
    return os.str();
}

/// Every parameter and buffer of `net` in PyTorch's state_dict order (module by module, each
/// module's parameters then its buffers).
std::vector<std::pair<std::string, torch::Tensor>> RegbenchTensors(torch::nn::Module& net) {
    std::vector<std::pair<std::string, torch::Tensor>> out;
    for (const auto& m : net.named_modules("", true)) {
        const std::string prefix = m.key().empty() ? "" : m.key() + ".";
        for (const auto& p : m.value()->named_parameters(false))
            out.emplace_back(prefix + p.key(), p.value());
        for (const auto& b : m.value()->named_buffers(false))
            out.emplace_back(prefix + b.key(), b.value());
    }
    return out;
}

const torch::Tensor* Find(const StateDict& sd, const std::string& key) {
    for (const auto& [k, v] : sd) {
        if (k == key) return &v;
    }
    return nullptr;
}

/// The family `arch` when it has an authors' format; else std::invalid_argument naming `flag`.
const NetworkFamily& AuthorsFamily(const std::string& arch, const std::string& flag) {
    const auto formats = AuthorsFormats();
    for (const auto& f : formats) {
        if (f == arch) return FindFamily(arch);
    }
    std::string known;
    for (std::size_t j = 0; j < formats.size(); ++j) {
        known += (j == 0 ? "" : j + 1 == formats.size() ? " or " : ", ") + formats[j];
    }
    throw std::invalid_argument(flag + " must be " + known + ", got '" + arch + "'");
}

}  // namespace

void RefuseAuthorsFile(const std::string& file, const std::string& what) {
    throw std::runtime_error(file + ": " + what);
}

const torch::Tensor& RequireAuthorsTensor(const StateDict& sd, const std::string& key,
                                          int64_t dims, const std::string& file,
                                          const std::string& network) {
    const torch::Tensor* t = Find(sd, key);
    if (t == nullptr) {
        std::string first;
        for (size_t j = 0; j < sd.size() && j < 3; ++j) first += (j ? ", " : "") + sd[j].first;
        RefuseAuthorsFile(file, "has no tensor " + key + ": not " + network +
                                    " state dict (its tensors are " + first +
                                    (sd.size() > 3 ? ", ..." : "") + ")");
    }
    if (t->dim() != dims) {
        RefuseAuthorsFile(file, "tensor " + key + " has shape " + ShapeString(t->sizes()) +
                                    ", expected " + std::to_string(dims) + " dimensions");
    }
    return *t;
}

std::vector<std::pair<std::string, std::string>> AuthorsKeyMapping(const std::string& from,
                                                                   const nlohmann::json& config) {
    const AuthorsFormat& format = *AuthorsFamily(from, "--from").authors;
    const auto net = MakeNetFromConfig(config);
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& [rb, tensor] : RegbenchTensors(*net)) {
        (void)tensor;
        out.emplace_back(format.authors_name ? format.authors_name(rb) : rb, rb);
    }
    if (format.module_rank) {
        std::stable_sort(out.begin(), out.end(), [&](const auto& a, const auto& b) {
            return format.module_rank(a.first) < format.module_rank(b.first);
        });
    }
    return out;
}

std::vector<ImportSetting> AuthorsImportSettings(const std::string& from) {
    return AuthorsFamily(from, "--from").authors->settings;
}

std::vector<ImportPreset> AuthorsImportPresets(const std::string& from) {
    return AuthorsFamily(from, "--from").authors->presets;
}

ResolvedImportSettings ResolveImportSettings(const ImportOptions& options) {
    const AuthorsFormat& format = *AuthorsFamily(options.from, "--from").authors;
    const std::string who = options.from + " import";
    std::string keys;
    for (const auto& s : format.settings) keys += (keys.empty() ? "" : ", ") + s.key;
    if (keys.empty()) keys = "none: its tensors fix the whole network";
    ResolvedImportSettings out;
    std::set<std::string> given;
    const auto set = [&](const std::string& key, const nlohmann::json& value,
                         const std::string& where) {
        const auto it = std::find_if(format.settings.begin(), format.settings.end(),
                                     [&](const ImportSetting& s) { return s.key == key; });
        if (it == format.settings.end()) {
            throw std::invalid_argument(who + ": " + where + " names unknown setting '" + key +
                                        "' (" + options.from + " settings: " + keys + ")");
        }
        const nlohmann::json& d = it->default_value;
        const bool same_type = (d.is_number() && value.is_number()) ||
                               (d.is_string() && value.is_string()) ||
                               (d.is_boolean() && value.is_boolean());
        if (!same_type || (d.is_number_integer() && !value.is_number_integer())) {
            throw std::invalid_argument(who + ": " + where + " setting " + key + " = " +
                                        value.dump() + " is not of the type of its default " +
                                        d.dump());
        }
        out.values[key] = value;
        given.insert(key);
    };
    for (const auto& s : format.settings) out.values[s.key] = s.default_value;
    if (!options.preset.empty()) {
        const auto it =
            std::find_if(format.presets.begin(), format.presets.end(),
                         [&](const ImportPreset& p) { return p.name == options.preset; });
        if (it == format.presets.end()) {
            std::string names;
            for (const auto& p : format.presets) names += (names.empty() ? "" : ", ") + p.name;
            throw std::invalid_argument(who + ": unknown preset '" + options.preset + "' (" +
                                        options.from +
                                        " presets: " + (names.empty() ? "none" : names) + ")");
        }
        for (const auto& [k, v] : it->values.items()) set(k, v, "preset " + it->name);
    }
    if (!options.settings.is_object()) {
        throw std::invalid_argument(who + ": settings must be a JSON object");
    }
    for (const auto& [k, v] : options.settings.items()) set(k, v, "--setting");
    for (const auto& s : format.settings) {
        if (!given.count(s.key)) out.assumed.push_back(s.key);
    }
    return out;
}

nlohmann::json InferAuthorsConfig(const StateDict& sd, const std::string& file,
                                  const ImportOptions& options) {
    return AuthorsFamily(options.from, "--from")
        .authors->infer_config(sd, file, ResolveImportSettings(options).values);
}

// Long on purpose: the import is one checked sequence (read, strip "module.", map every tensor,
// refuse leftovers, write, describe) whose steps each use what the previous one produced; the
// key mapping itself is AuthorsKeyMapping.
nlohmann::json ImportAuthorsCheckpoint(const std::string& pth, const std::string& out_dir,
                                       const ImportOptions& options) {
    const AuthorsFormat& format = *AuthorsFamily(options.from, "--from").authors;
    const ResolvedImportSettings settings = ResolveImportSettings(options);  // before reading
    TorchSaveContents contents = ReadTorchSaveFile(pth);
    StateDict& sd = contents.tensors;
    // nn.DataParallel saves every key under "module.".
    const bool data_parallel = std::all_of(
        sd.begin(), sd.end(), [](const auto& kv) { return kv.first.rfind("module.", 0) == 0; });
    if (data_parallel) {
        for (auto& kv : sd) kv.first = kv.first.substr(7);
    }
    const nlohmann::json config = format.infer_config(sd, pth, settings.values);
    std::shared_ptr<RegistrationNet> net;
    try {  // sizes inferred from shapes are checked by the family's bounds, named by file
        net = MakeNetFromConfig(config);
    } catch (const c10::Error& e) {
        RefuseAuthorsFile(pth,
                          std::string("cannot build its model: ") + e.what_without_backtrace());
    } catch (const std::exception& e) {
        RefuseAuthorsFile(pth, std::string("cannot build its model: ") + e.what());
    }
    std::map<std::string, torch::Tensor> rb;
    for (const auto& [k, v] : RegbenchTensors(*net)) rb[k] = v;
    const auto mapping = AuthorsKeyMapping(options.from, config);

    std::vector<std::string> problems;
    std::set<std::string> expected;
    std::vector<std::string> defaulted;
    for (const auto& [au, r] : mapping) {
        expected.insert(au);
        const torch::Tensor* t = Find(sd, au);
        const torch::Tensor& target = rb.at(r);
        if (t == nullptr) {
            // Files of PyTorch < 0.4.1 have no BatchNorm step counters; eval never reads them.
            if (au.size() > 19 && au.compare(au.size() - 19, 19, "num_batches_tracked") == 0) {
                defaulted.push_back(au);
                continue;
            }
            problems.push_back("missing tensor " + au + " " + ShapeString(target.sizes()));
        } else if (t->sizes() != target.sizes()) {
            problems.push_back("tensor " + au + " has shape " + ShapeString(t->sizes()) +
                               ", expected " + ShapeString(target.sizes()));
        } else if (target.is_floating_point() != t->is_floating_point()) {
            problems.push_back("tensor " + au + " has type " +
                               std::string(c10::toString(t->scalar_type())) + ", expected " +
                               c10::toString(target.scalar_type()));
        }
    }
    for (const auto& [k, v] : sd) {
        if (expected.count(k) == 0)
            problems.push_back("unexpected tensor " + k + " " + ShapeString(v.sizes()));
    }
    if (!problems.empty()) {
        std::string msg = "does not fit " + config.at("name").get<std::string>() + " " +
                          nlohmann::json(config).dump() + ":";
        for (size_t j = 0; j < problems.size() && j < 30; ++j) msg += "\n  " + problems[j];
        if (problems.size() > 30)
            msg += "\n  ... and " + std::to_string(problems.size() - 30) + " more";
        RefuseAuthorsFile(pth, msg);
    }
    // Poisoned weights (NaN, Inf, |w| > kMaxAbsWeight) imported with exit 0 and ran silently.
    for (const auto& [au, r] : mapping) {
        (void)r;
        const torch::Tensor* t = Find(sd, au);
        const std::string problem = t != nullptr ? WeightValueProblem(*t) : "";
        if (!problem.empty()) {
            RefuseAuthorsFile(pth, "tensor " + au + " " + problem +
                                       "; refusing to import poisoned weights");
        }
    }
    nlohmann::json map_json = nlohmann::json::array();
    {
        torch::NoGradGuard no_grad;
        for (const auto& [au, r] : mapping) {
            const torch::Tensor* t = Find(sd, au);
            if (t != nullptr) rb.at(r).copy_(t->to(rb.at(r).scalar_type()));
            map_json.push_back(
                {{"source", au}, {"regbench", r}, {"shape", rb.at(r).sizes().vec()}});
        }
    }
    nlohmann::json meta;
    meta["config"] = config;
    meta["imported_from"] = {
        {"file", fs::absolute(pth).lexically_normal().string()},
        // Of the bytes imported, not of the name again (read once: issue 55).
        {"sha256", contents.sha256},
        {"bytes", contents.bytes},
        {"format", contents.format},
        {"from", options.from},
        {"module", format.module},
        {"wrapper_key", contents.wrapper},
        {"stripped_prefix", data_parallel ? "module." : ""},
        {"defaulted_to_zero", defaulted},
        {"preset", options.preset},
        {"settings", settings.values},
        {"assumed_settings", settings.assumed},
    };
    meta["mapping"] = map_json;
    SaveCheckpoint(out_dir, *net, meta);
    return ReadCheckpointJson(out_dir);
}

StateDict ExportAuthorsStateDict(const std::string& dir, const std::string& to) {
    const AuthorsFormat& format = *AuthorsFamily(to, "--to").authors;
    const nlohmann::json j = ReadCheckpointJson(dir);
    const nlohmann::json config = j.contains("config") ? j.at("config") : j.at("model_config");
    const std::string arch = config.value("arch", "");
    const std::string where = (fs::path(dir) / kCheckpointJson).string();
    if (arch != to) RefuseAuthorsFile(where, "holds a " + arch + " model, not " + to);
    if (format.check_export) format.check_export(config, where);
    const auto net = LoadNetFromCheckpoint(dir);
    std::map<std::string, torch::Tensor> rb;
    for (const auto& [k, v] : RegbenchTensors(*net)) rb[k] = v;
    StateDict out;
    for (const auto& [au, r] : AuthorsKeyMapping(to, config))
        out.emplace_back(au, rb.at(r).detach().clone());
    return out;
}

AuthorsPth ExportAuthorsPth(const std::string& dir, const std::string& to) {
    const StateDict sd = ExportAuthorsStateDict(dir, to);
    return {WriteTorchSaveZip(sd), sd.size()};
}

}  // namespace regbench::networks
