#include "experiments/weights_manifest.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "baselines/learned.hpp"
#include "core/json_limits.hpp"
#include "core/registration.hpp"
#include "core/sha256.hpp"
#ifdef REGBENCH_HAVE_LEARNED
#include "networks/checkpoint/authors_checkpoint.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/family.hpp"
#endif

namespace regbench {
namespace fs = std::filesystem;
namespace {

const std::set<std::string> kEntryKeys = {"experiments", "methods",      "label",
                                          "checkpoint",  "authors_file", "from",
                                          "preset",      "settings",     "comment"};

[[noreturn]] void Refuse(const std::string& where, const std::string& what) {
    throw std::invalid_argument("weights manifest " + where + ": " + what);
}

std::vector<std::string> StringList(const nlohmann::json& e, const char* key,
                                    const std::string& where) {
    if (!e.contains(key) || !e[key].is_array() || e[key].empty()) {
        Refuse(where, std::string("needs \"") + key + "\": a non-empty list of names");
    }
    std::vector<std::string> out;
    for (const auto& v : e[key]) {
        if (!v.is_string() || v.get<std::string>().empty())
            Refuse(where, std::string("\"") + key + "\" holds " + v.dump() + ", not a name");
        out.push_back(v.get<std::string>());
    }
    return out;
}

std::string OptionalString(const nlohmann::json& e, const char* key, const std::string& where) {
    if (!e.contains(key)) return "";
    if (!e[key].is_string()) Refuse(where, std::string("\"") + key + "\" must be a string");
    return e[key].get<std::string>();
}

/// `path` relative to the manifest's folder unless absolute.
std::string Resolve(const std::string& path, const fs::path& base) {
    if (path.empty() || fs::path(path).is_absolute()) return path;
    return (base / path).lexically_normal().string();
}

/// A folder name for an entry's import: its label, else "<from>-entry<N>", made safe.
std::string ImportFolderName(const WeightsEntry& e, std::size_t index) {
    std::string name = e.label.empty() ? e.from + "-entry" + std::to_string(index + 1) : e.label;
    for (char& c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.')
            c = '_';
    }
    if (name.empty() || name[0] == '.') name = "_" + name;
    return name;
}

bool Contains(const std::vector<std::string>& v, const std::string& s) {
    return std::find(v.begin(), v.end(), s) != v.end();
}

}  // namespace

std::string WeightsChoice::Describe() const {
    return label + " (" + source + ", sha256 " + sha256.substr(0, 12) + ")";
}

WeightsManifest ReadWeightsManifest(const std::string& path) {
    const nlohmann::json j = ReadJsonFileBounded(path, "weights manifest " + path);
    if (!j.is_object() || j.value("format", "") != "regbench-weights") {
        Refuse(path, "not a weights manifest (needs \"format\": \"regbench-weights\")");
    }
    for (const auto& [key, value] : j.items()) {
        (void)value;
        if (key != "format" && key != "format_version" && key != "entries" && key != "comment")
            Refuse(path, "unknown key \"" + key + "\" (format, format_version, entries, comment)");
    }
    if (j.value("format_version", 0) != 1) Refuse(path, "format_version must be 1");
    if (!j.contains("entries") || !j["entries"].is_array()) {
        Refuse(path, "needs \"entries\": a list");
    }
    const fs::path base = fs::absolute(path).parent_path();
    WeightsManifest m;
    m.path = path;
    std::size_t n = 0;
    for (const auto& e : j["entries"]) {
        ++n;
        std::string where = path + ": entry " + std::to_string(n);
        if (!e.is_object()) Refuse(where, "is not a JSON object");
        WeightsEntry w;
        w.label = OptionalString(e, "label", where);
        if (!w.label.empty()) where += " (" + w.label + ")";
        w.where = where;
        for (const auto& [key, value] : e.items()) {
            (void)value;
            if (!kEntryKeys.count(key)) {
                std::string known;
                for (const auto& k : kEntryKeys) known += (known.empty() ? "" : ", ") + k;
                Refuse(where, "unknown key \"" + key + "\" (" + known + ")");
            }
        }
        w.experiments = StringList(e, "experiments", where);
        w.methods = StringList(e, "methods", where);
        w.checkpoint = Resolve(OptionalString(e, "checkpoint", where), base);
        w.authors_file = Resolve(OptionalString(e, "authors_file", where), base);
        w.from = OptionalString(e, "from", where);
        w.preset = OptionalString(e, "preset", where);
        if (e.contains("settings")) {
            if (!e["settings"].is_object()) Refuse(where, "\"settings\" must be a JSON object");
            w.settings = e["settings"];
        }
        if (w.checkpoint.empty() == w.authors_file.empty()) {
            Refuse(where,
                   "needs exactly one of \"checkpoint\" (a regbench checkpoint folder) "
                   "and \"authors_file\" (an authors' .pth, with \"from\")");
        }
        if (!w.checkpoint.empty() &&
            (!w.from.empty() || !w.preset.empty() || !w.settings.empty())) {
            Refuse(where,
                   "\"from\", \"preset\" and \"settings\" go with \"authors_file\" only "
                   "(a checkpoint folder holds its settings)");
        }
        if (!w.authors_file.empty() && w.from.empty()) {
            Refuse(where, "\"authors_file\" needs \"from\": the family whose authors saved it");
        }
        m.entries.push_back(std::move(w));
    }
    return m;
}

std::string DefaultWeightsManifestPath() {
#ifdef REGBENCH_HAVE_LEARNED
    const std::string path = ShippedCheckpointDir("weights.json");
    return fs::exists(path) ? path : "";
#else
    return "";  // no learned methods, nothing to choose
#endif
}

WeightsManifest OnlyTargetsOf(WeightsManifest manifest,
                              const std::vector<WeightsTarget>& targets) {
    std::vector<WeightsEntry> kept;
    for (auto& e : manifest.entries) {
        std::vector<std::string> known;
        for (const auto& x : e.experiments) {
            const bool has = std::any_of(targets.begin(), targets.end(), [&](const auto& t) {
                return t.experiment == x || t.table == x;
            });
            if (has) known.push_back(x);
        }
        e.experiments = known;
        if (!known.empty()) kept.push_back(std::move(e));
    }
    manifest.entries = std::move(kept);
    return manifest;
}

// Long on purpose: one checked sequence (every entry against the plan, then the imports, then
// every target's learned methods), each step using what the one before established.
WeightsPlan ResolveWeights(const WeightsManifest& manifest,
                           const std::vector<WeightsTarget>& targets, const std::string& import_dir,
                           std::ostream& log, bool may_import) {
    WeightsPlan plan;
#ifdef REGBENCH_HAVE_LEARNED
    std::vector<std::string> learned;
    for (const auto& m : LearnedMethodInfos()) learned.push_back(m.name);
    // 1. Every entry against the plan and the files, before anything is imported.
    for (const auto& e : manifest.entries) {
        for (const auto& x : e.experiments) {
            const bool known = std::any_of(targets.begin(), targets.end(), [&](const auto& t) {
                return t.experiment == x || t.table == x;
            });
            if (!known) {
                std::string ids;
                for (const auto& t : targets) ids += (ids.empty() ? "" : ", ") + t.experiment;
                Refuse(e.where, "names experiment '" + x + "', which this run does not have (" +
                                    ids + ", or their table ids)");
            }
        }
        for (const auto& m : e.methods) {
            if (!Contains(learned, m)) {
                std::string names;
                for (const auto& l : learned) names += (names.empty() ? "" : ", ") + l;
                Refuse(e.where,
                       "names method '" + m + "', which is not a learned method (" + names + ")");
            }
            for (const auto& t : targets) {
                if ((Contains(e.experiments, t.experiment) || Contains(e.experiments, t.table)) &&
                    !Contains(t.methods, m)) {
                    Refuse(e.where, "names method '" + m + "' for " + t.experiment +
                                        ", whose table (" + t.table + ") does not run it");
                }
            }
        }
        if (!e.checkpoint.empty() && !fs::exists(fs::path(e.checkpoint) / "checkpoint.json")) {
            Refuse(e.where, "checkpoint " + e.checkpoint +
                                " is not a regbench checkpoint folder (no checkpoint.json)");
        }
        if (!e.authors_file.empty()) {
            if (!fs::is_regular_file(e.authors_file)) {
                Refuse(e.where, "authors_file " + e.authors_file + ": no such file");
            }
            const auto formats = networks::AuthorsFormats();
            if (!Contains(formats, e.from)) {
                std::string names;
                for (const auto& f : formats) names += (names.empty() ? "" : ", ") + f;
                Refuse(e.where, "\"from\": '" + e.from + "' is no authors' format (" + names + ")");
            }
            networks::ImportOptions o{e.from, e.preset, e.settings};
            try {
                networks::ResolveImportSettings(o);
            } catch (const std::exception& ex) {
                Refuse(e.where, ex.what());
            }
        }
    }
    // 2. The authors' files, each imported once into the report folder.
    std::vector<std::string> dirs(manifest.entries.size());
    for (std::size_t i = 0; i < manifest.entries.size(); ++i) {
        const WeightsEntry& e = manifest.entries[i];
        if (e.authors_file.empty()) {
            dirs[i] = e.checkpoint;
            continue;
        }
        // Named by the file's and the settings' content, so an import is never replaced: an
        // earlier invocation's is reused, another file or setting gets a folder of its own.
        const networks::ImportOptions o{e.from, e.preset, e.settings};
        const std::string key = Sha256File(e.authors_file) + " " + e.from + " " + e.preset + " " +
                                networks::ResolveImportSettings(o).values.dump();
        const fs::path dir =
            fs::path(import_dir) / (ImportFolderName(e, i) + "-" + Sha256Hex(key).substr(0, 12));
        dirs[i] = dir.string();
        if (fs::exists(dir / "checkpoint.json")) continue;
        if (!may_import) {
            Refuse(e.where, e.authors_file + " is not imported into " + dir.string() +
                                " yet: run `reproduce --prepare` with this manifest first");
        }
        fs::create_directories(import_dir);
        log << "reproduce: importing " << e.authors_file << " (--from " << e.from
            << (e.preset.empty() ? "" : " --preset " + e.preset) << ") into " << dir.string()
            << "\n";
        try {
            networks::ImportAuthorsCheckpoint(e.authors_file, dir.string(), o);
        } catch (const std::exception& ex) {
            Refuse(e.where, ex.what());
        }
    }
    // 3. Every target's learned methods: the last entry naming them, else the shipped folder.
    std::map<std::string, CheckpointInfo> described;  // sha256 of each folder once
    for (const auto& t : targets) {
        for (const auto& m : t.methods) {
            if (!Contains(learned, m)) continue;
            WeightsChoice c;
            c.checkpoint = DefaultCheckpointDir(m);
            std::string label;
            for (std::size_t i = 0; i < manifest.entries.size(); ++i) {
                const WeightsEntry& e = manifest.entries[i];
                if ((Contains(e.experiments, t.experiment) || Contains(e.experiments, t.table)) &&
                    Contains(e.methods, m)) {
                    c.checkpoint = dirs[i];
                    label = e.label;
                }
            }
            c.is_default =
                fs::weakly_canonical(c.checkpoint) == fs::weakly_canonical(DefaultCheckpointDir(m));
            if (!fs::exists(fs::path(c.checkpoint) / "checkpoint.json")) {
                continue;  // a method without its shipped checkpoint is left out by the run
            }
            if (!described.count(c.checkpoint)) {
                described.emplace(c.checkpoint, DescribeCheckpoint(c.checkpoint));
            }
            const CheckpointInfo& info = described.at(c.checkpoint);
            c.label = label.empty() ? info.label : label + ": " + info.label;
            c.sha256 = info.sha256;
            c.source = info.source;
            plan[t.experiment][m] = c;
        }
    }
#else
    (void)targets;
    (void)import_dir;
    (void)log;
    (void)may_import;
    if (!manifest.entries.empty()) {
        Refuse(manifest.entries.front().where, "this build has no learned methods (LibTorch)");
    }
#endif
    return plan;
}

nlohmann::json WeightsPlanJson(const WeightsManifest& manifest, const WeightsPlan& plan) {
    nlohmann::json choices = nlohmann::json::object();
    for (const auto& [experiment, methods] : plan) {
        for (const auto& [method, c] : methods) {
            choices[experiment][method] = {{"checkpoint", c.checkpoint},
                                           {"label", c.label},
                                           {"sha256", c.sha256},
                                           {"source", c.source}};
        }
    }
    return {{"manifest", manifest.path.empty() ? "" : fs::absolute(manifest.path).string()},
            {"manifest_sha256", manifest.path.empty() ? "" : Sha256File(manifest.path)},
            {"weights", choices}};
}

void CheckSameWeights(const nlohmann::json& recorded, const nlohmann::json& now,
                      const std::string& where) {
    const nlohmann::json was = recorded.value("weights", nlohmann::json::object());
    const nlohmann::json is = now.value("weights", nlohmann::json::object());
    if (was == is) return;
    std::string first;
    for (const auto& op : nlohmann::json::diff(was, is)) {
        first = op.value("path", std::string("/"));
        break;
    }
    const nlohmann::json::json_pointer p(first);
    const auto at = [&](const nlohmann::json& j) {
        return j.contains(p) ? j.at(p).dump() : std::string("(none)");
    };
    throw std::invalid_argument(
        where + " was run with other weights (first difference at " + first + ": " + at(was) +
        " then, " + at(is) +
        " now): continuing would mix checkpoints in one table; give a new --out, or "
        "remove the folder to start over");
}

}  // namespace regbench
