#include "experiments/experiment_file.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <stdexcept>

#include "core/json_limits.hpp"
#include "protocols/pair_protocols.hpp"
#include "reports/paper_report.hpp"

namespace regbench {
namespace {

[[noreturn]] void Fail(const std::string& file, const std::string& key, const std::string& why) {
    throw std::invalid_argument("experiment file " + file + ": key '" + key + "' " + why);
}

/// One JSON object of an experiment file, read key by key; every message names the file and
/// the key's path (e.g. "experiments[1].pairs.scale").
class Reader {
public:
    Reader(const nlohmann::json& j, std::string file, std::string path)
        : j_(j), file_(std::move(file)), path_(std::move(path)) {
        if (!j_.is_object()) Fail(file_, Where(), "must be a JSON object, got " + j_.dump());
    }
    /// Refuses keys not in `known` ("comment" is allowed everywhere).
    void Only(std::initializer_list<const char*> known) const {
        for (const auto& item : j_.items()) {
            const bool ok = item.key() == "comment" ||
                            std::any_of(known.begin(), known.end(),
                                        [&](const char* k) { return item.key() == k; });
            if (ok) continue;
            std::string list;
            for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
            Fail(file_, Key(item.key().c_str()), "is not known (known: " + list + ", comment)");
        }
    }
    const nlohmann::json* Find(const char* key, bool required) const {
        const auto it = j_.find(key);
        if (it != j_.end()) return &*it;
        if (required) Fail(file_, Key(key), "is required");
        return nullptr;
    }
    std::string Str(const char* key, bool required = false) const {
        const nlohmann::json* v = Find(key, required);
        if (v == nullptr) return "";
        if (!v->is_string() || v->get<std::string>().empty()) Expect(key, *v, "a non-empty string");
        return v->get<std::string>();
    }
    bool Bool(const char* key) const {
        const nlohmann::json* v = Find(key, false);
        if (v != nullptr && !v->is_boolean()) Expect(key, *v, "true or false");
        return v != nullptr && v->get<bool>();
    }
    std::size_t Count(const char* key, std::size_t fallback) const {
        const nlohmann::json* v = Find(key, false);
        if (v == nullptr) return fallback;
        return Count(key, *v);
    }
    std::size_t Count(const char* key, const nlohmann::json& v) const {
        // The one integer rule of core/params.hpp: 2 and 2.0 are whole, 2.5 is not.
        const double d = v.is_number() ? v.get<double>() : -1.0;
        if (!(d >= 0.0 && d <= 1e9 && std::trunc(d) == d))
            Expect(key, v, "a whole number in [0, 1e9]");
        return static_cast<std::size_t>(d);
    }
    std::vector<std::string> Strings(const char* key) const {
        const nlohmann::json* v = Find(key, false);
        if (v == nullptr) return {};
        std::vector<std::string> out;
        const bool ok = v->is_array() && !v->empty() &&
                        std::all_of(v->begin(), v->end(), [](const nlohmann::json& s) {
                            return s.is_string() && !s.get<std::string>().empty();
                        });
        if (!ok) Expect(key, *v, "a non-empty list of non-empty strings");
        for (const auto& s : *v) out.push_back(s.get<std::string>());
        return out;
    }
    /// The objects of list `key`, each with its own path ("key[i]").
    std::vector<Reader> Objects(const char* key) const {
        const nlohmann::json* v = Find(key, false);
        std::vector<Reader> out;
        if (v == nullptr) return out;
        if (!v->is_array() || v->empty()) Expect(key, *v, "a non-empty list of objects");
        for (std::size_t i = 0; i < v->size(); ++i)
            out.emplace_back((*v)[i], file_, Key(key) + "[" + std::to_string(i) + "]");
        return out;
    }
    Reader Object(const char* key) const { return Reader(*Find(key, true), file_, Key(key)); }
    [[noreturn]] void Expect(const char* key, const nlohmann::json& v, const char* what) const {
        Fail(file_, Key(key), std::string("must be ") + what + ", got " + v.dump());
    }
    /// Runs `check` (a parser of this key's value) and rethrows its error naming the key.
    template <class F>
    void Check(const char* key, F&& check) const {
        try {
            check();
        } catch (const std::exception& e) {
            Fail(file_, Key(key), std::string("is not valid: ") + e.what());
        }
    }
    std::string Key(const char* key) const { return path_.empty() ? key : path_ + "." + key; }
    std::string Where() const { return path_.empty() ? "(top level)" : path_; }
    const nlohmann::json& json() const { return j_; }
    const std::string& file() const { return file_; }

private:
    const nlohmann::json& j_;
    std::string file_;
    std::string path_;
};

PairCount ReadPairCount(const Reader& e) {
    PairCount c;
    const nlohmann::json* v = e.Find("pairs", false);
    if (v == nullptr) return c;
    if (v->is_number()) {
        c.fixed = e.Count("pairs", *v);
        if (c.fixed == 0) e.Expect("pairs", *v, "at least 1");
        return c;
    }
    const Reader p = e.Object("pairs");
    p.Only({"scale", "min", "quick"});
    if (const nlohmann::json* s = p.Find("scale", false)) {
        if (!s->is_number() || !(s->get<double>() > 0.0) || !(s->get<double>() <= 1e6))
            p.Expect("scale", *s, "a number in (0, 1e6]");
        c.scale = s->get<double>();
    }
    c.min = p.Count("min", 0);
    c.quick = p.Count("quick", 0);
    return c;
}

ExperimentSpec ReadExperiment(const Reader& e) {
    e.Only({"id", "group", "protocol", "split", "dataset", "root", "fallback_note", "pairing",
            "root_pairing", "noise_free", "seed_offset", "pairs", "sweep"});
    ExperimentSpec s;
    s.id = e.Str("id", true);
    if (s.id.find_first_of("/\\") != std::string::npos || s.id[0] == '.')
        e.Expect("id", s.id, "a file stem (no '/', no leading '.')");
    s.group = e.Str("group");
    s.protocol = e.Str("protocol", true);
    e.Check("protocol", [&] { (void)ParseProtocol(s.protocol); });
    s.split = e.Str("split", true);
    s.dataset = e.Str("dataset", true);
    s.root = e.Str("root");
    if (!s.root.empty() && s.root != "modelnet40" && s.root != "7scenes" && s.root != "icl-nuim")
        e.Expect("root", s.root, "one of \"modelnet40\", \"7scenes\", \"icl-nuim\"");
    s.fallback_note = e.Str("fallback_note");
    for (const auto& field :
         {std::pair{"pairing", &s.pairing}, {"root_pairing", &s.root_pairing}}) {
        std::string& value = *field.second;
        value = e.Str(field.first);
        if (!value.empty()) e.Check(field.first, [&] { (void)ParsePairing(value); });
    }
    s.noise_free = e.Bool("noise_free");
    s.seed_offset = e.Count("seed_offset", 0);
    s.pairs = ReadPairCount(e);
    s.sweep = e.Strings("sweep");
    if (!s.sweep.empty() && !s.group.empty())
        e.Expect("group", s.group, "absent for a sweep (its groups are the sweep's levels)");
    return s;
}

VariantSpec ReadVariants(const Reader& v) {
    v.Only({"kind", "method", "model", "pairs_of", "rows"});
    VariantSpec s;
    s.kind = v.Str("kind", true);
    s.method = v.Str("method", true);
    s.model = v.Str("model", true);
    s.pairs_of = v.Str("pairs_of");
    (void)v.Find("rows", true);
    for (const Reader& r : v.Objects("rows")) {
        r.Only({"row", "config"});
        const nlohmann::json& config = *r.Find("config", true);
        if (!config.is_object()) r.Expect("config", config, "a JSON object of config overrides");
        s.rows.push_back({r.Str("row", true), config});
    }
    return s;
}

bool IsPaperTable(const std::string& id) {
    if (id == "table6_inference_time") return true;
    const auto& specs = PaperTableSpecs();
    return std::any_of(specs.begin(), specs.end(), [&](const auto& s) { return s.id == id; });
}

}  // namespace

ExperimentFile ParseExperimentFile(const nlohmann::json& j, const std::string& file) {
    const Reader r(j, file, "");
    r.Only({"table", "title", "caption", "methods", "learned", "metrics", "experiments", "variants",
            "timing_of"});
    ExperimentFile f;
    f.file = file;
    f.table = r.Str("table", true);
    f.title = r.Str("title", true);
    f.caption = r.Str("caption");
    f.methods = r.Strings("methods");
    f.learned = r.Strings("learned");
    f.metrics = r.Strings("metrics");
    for (const Reader& e : r.Objects("experiments")) f.experiments.push_back(ReadExperiment(e));
    if (r.Find("variants", false) != nullptr) f.variants = ReadVariants(r.Object("variants"));
    f.timing_of = r.Str("timing_of");
    if (f.experiments.empty() && !f.variants && f.timing_of.empty() && !IsPaperTable(f.table)) {
        Fail(file, "experiments",
             "is required: table '" + f.table +
                 "' is not one of the paper's, so only this file's experiments can fill it");
    }
    return f;
}

ExperimentFile ReadExperimentFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("experiment file " + path + ": cannot open");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    nlohmann::json j;
    try {
        j = ParseJsonBounded(text, "experiment file " + path);
    } catch (const std::exception& e) {
        throw std::invalid_argument("experiment file " + path + ": not valid JSON: " + e.what());
    }
    return ParseExperimentFile(j, path);
}

void CheckExperimentFiles(const std::vector<ExperimentFile>& files) {
    std::set<std::string> tables;
    std::map<std::string, std::string> ids;  // experiment id -> its file
    for (const auto& f : files) {
        if (!tables.insert(f.table).second)
            Fail(f.file, "table", "'" + f.table + "' is another file's table too");
        for (const auto& e : f.experiments) {
            if (!ids.emplace(e.id, f.file).second)
                Fail(f.file, "experiments", "repeats id '" + e.id + "' of " + ids[e.id]);
        }
    }
    for (const auto& f : files) {
        const auto refer = [&](const std::string& key, const std::string& id) {
            if (!id.empty() && ids.count(id) == 0)
                Fail(f.file, key, "names experiment '" + id + "', which no file of this run has");
        };
        refer("timing_of", f.timing_of);
        if (f.variants) refer("variants.pairs_of", f.variants->pairs_of);
    }
}

const std::vector<ExperimentFile>& PaperPlan() {
    static const std::vector<ExperimentFile> kPlan = [] {
        std::vector<ExperimentFile> plan;
        for (const auto& f : EmbeddedPlanFiles()) {
            const std::string name = std::string("experiments/plan/") + f.name;
            plan.push_back(ParseExperimentFile(ParseJsonBounded(f.text, name), name));
        }
        CheckExperimentFiles(plan);
        return plan;
    }();
    return kPlan;
}

}  // namespace regbench
