#include "experiments/experiment_file.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <stdexcept>

#include "core/json_limits.hpp"
#include "core/params.hpp"
#include "protocols/pair_protocols.hpp"
#include "reports/paper_report.hpp"
#include "runners/registry.hpp"

namespace regbench {

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(PairCount, scale, min, quick, count)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ExperimentSpec, id, group, protocol, split, dataset,
                                                root, fallback_note, pairing, root_pairing,
                                                noise_free, seed_offset, pairs, sweep,
                                                protocol_options, comment)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Variant, row, config)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(VariantSpec, kind, method, model, pairs_of, rows,
                                                rows_are_groups, comment)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(TimingVariant, row, method, params, comment)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ExperimentFile, table, title, caption, methods,
                                                learned, metrics, experiments, variants, timing_of,
                                                timing_variants, comment)

namespace {

/// Runs `check` (a parser of the value of `key`) and rethrows its error naming the key.
template <class F>
void Check(const std::string& what, const char* key, F&& check) {
    try {
        check();
    } catch (const std::exception& e) {
        Require(false, what, key, std::string("is not valid: ") + e.what());
    }
}

/// A name used as a file stem (tables/<table>.md, pairs/<id>.h5): no folder separator, no
/// leading '.', no "..": `"table": "../../x"` wrote outside the report folder.
bool IsFileStem(const std::string& name) {
    return !name.empty() && name.find_first_of("/\\") == std::string::npos && name[0] != '.' &&
           name.find("..") == std::string::npos;
}

/// A method name a file may list: registered in this build, or one of its `learned` methods
/// (left out with a note when this build or its checkpoints cannot run them).
void CheckMethodName(const ExperimentFile& f, const std::string& what, const char* key,
                     const std::string& name) {
    if (std::find(f.learned.begin(), f.learned.end(), name) != f.learned.end()) return;
    Check(what, key, [&] { (void)FindMethod(name); });
}

/// ParseConfig of `j` without its keys `nested` (their values are parsed on their own, so a
/// message names the key inside them).
template <class T>
T ParseWithout(const nlohmann::json& j, const std::string& what, std::vector<const char*> nested) {
    nlohmann::json rest = j;
    for (const char* key : nested) {
        if (rest.is_object()) rest.erase(key);
    }
    return ParseConfig<T>(rest, what);
}

/// Each item of list `key` of `j`, parsed by `read`.
template <class Item, class F>
std::vector<Item> ReadList(const nlohmann::json& j, const std::string& what, const char* key,
                           F read) {
    const nlohmann::json list = j.value(key, nlohmann::json::array());
    Require(list.is_array(), what, key, "expects array, got " + list.dump());
    std::vector<Item> out;
    for (std::size_t i = 0; i < list.size(); ++i)
        out.push_back(read(list[i], what + ": " + key + "[" + std::to_string(i) + "]"));
    return out;
}

ExperimentSpec ReadExperiment(const nlohmann::json& j, const std::string& what) {
    auto s = ParseWithout<ExperimentSpec>(j, what, {"pairs"});
    s.pairs = ParseConfig<PairCount>(j.value("pairs", nlohmann::json()), what + ": pairs");
    for (const auto& [key, value] : {std::pair{"id", s.id},
                                     {"protocol", s.protocol},
                                     {"split", s.split},
                                     {"dataset", s.dataset}}) {
        Require(!value.empty(), what, key, "is required");
    }
    Require(IsFileStem(s.id), what, "id",
            "must be a file stem (no '/', no leading '.', no '..'), got '" + s.id + "'");
    Check(what, "protocol", [&] { (void)ParseProtocol(s.protocol); });
    Require(s.root.empty() || s.root == "modelnet40" || s.root == "7scenes" || s.root == "icl-nuim",
            what, "root", "must be modelnet40, 7scenes or icl-nuim, got '" + s.root + "'");
    if (!s.pairing.empty()) Check(what, "pairing", [&] { (void)ParsePairing(s.pairing); });
    if (!s.root_pairing.empty())
        Check(what, "root_pairing", [&] { (void)ParsePairing(s.root_pairing); });
    Require(s.pairs.scale > 0.0 && s.pairs.scale <= 1e6, what + ": pairs", "scale",
            "must be in (0, 1e6], got " + nlohmann::json(s.pairs.scale).dump());
    Require(s.sweep.empty() || s.group.empty(), what, "group",
            "must be absent for a sweep (its groups are the sweep's levels)");
    Check(what, "protocol_options", [&] { (void)ProtocolOptionsOf(s); });
    return s;
}

Variant ReadVariant(const nlohmann::json& j, const std::string& what) {
    auto v = ParseConfig<Variant>(j, what);
    Require(!v.row.empty(), what, "row", "is required");
    return v;
}

VariantSpec ReadVariants(const nlohmann::json& j, const std::string& what) {
    auto v = ParseWithout<VariantSpec>(j, what, {"rows"});
    v.rows = ReadList<Variant>(j, what, "rows", ReadVariant);
    for (const auto& [key, value] :
         {std::pair{"kind", v.kind}, {"method", v.method}, {"model", v.model}}) {
        Require(!value.empty(), what, key, "is required");
    }
    Require(!v.rows.empty(), what, "rows", "must list at least one variant");
    return v;
}

TimingVariant ReadTimingVariant(const nlohmann::json& j, const std::string& what) {
    auto v = ParseConfig<TimingVariant>(j, what);
    Require(!v.row.empty(), what, "row", "is required");
    Require(!v.method.empty(), what, "method", "is required");
    Require(v.params.is_object(), what, "params", "expects object, got " + v.params.dump());
    return v;
}

bool IsPaperTable(const std::string& id) {
    if (id == "table6_inference_time") return true;
    const auto& specs = PaperTableSpecs();
    return std::any_of(specs.begin(), specs.end(), [&](const auto& s) { return s.id == id; });
}

}  // namespace

ExperimentFile ParseExperimentFile(const nlohmann::json& j, const std::string& file) {
    const std::string what = "experiment file " + file;
    ExperimentFile f =
        ParseWithout<ExperimentFile>(j, what, {"experiments", "variants", "timing_variants"});
    f.file = file;
    Require(!f.table.empty(), what, "table", "is required");
    Require(IsFileStem(f.table), what, "table",
            "must be a file stem (no '/', no leading '.', no '..'), got '" + f.table + "'");
    Require(!f.title.empty(), what, "title", "is required");
    f.experiments = ReadList<ExperimentSpec>(j, what, "experiments", ReadExperiment);
    f.timing_variants = ReadList<TimingVariant>(j, what, "timing_variants", ReadTimingVariant);
    Require(f.timing_variants.empty() || !f.timing_of.empty(), what, "timing_variants",
            "needs timing_of (the experiment whose pairs they run on)");
    if (j.contains("variants")) f.variants = ReadVariants(j["variants"], what + ": variants");
    for (const auto& m : f.methods) CheckMethodName(f, what, "methods", m);
    for (std::size_t i = 0; i < f.timing_variants.size(); ++i) {
        CheckMethodName(f, what + ": timing_variants[" + std::to_string(i) + "]", "method",
                        f.timing_variants[i].method);
    }
    if (!f.variants.method.empty()) {
        CheckMethodName(f, what + ": variants", "method", f.variants.method);
    }
    Require(!f.experiments.empty() || !f.variants.rows.empty() || !f.timing_of.empty() ||
                IsPaperTable(f.table),
            what, "experiments",
            "is required: table '" + f.table +
                "' is not one of the paper's, so only this file's experiments can fill it");
    return f;
}

ProtocolOptions ProtocolOptionsOf(const ExperimentSpec& s) {
    ProtocolOptions o = ProtocolOptionsFromJson(s.protocol_options,
                                                DefaultProtocolOptions(ParseProtocol(s.protocol)));
    if (!s.pairing.empty()) o.pairing = ParsePairing(s.pairing);
    if (s.noise_free) o.noise_sigma = 0.0;
    ValidateProtocolOptions(o);
    return o;
}

ExperimentFile ReadExperimentFile(const std::string& path) {
    return ParseExperimentFile(ReadJsonFileBounded(path, "experiment file " + path), path);
}

void CheckExperimentFiles(const std::vector<ExperimentFile>& files) {
    std::set<std::string> tables;
    std::map<std::string, std::string> ids;  // experiment id -> its file
    for (const auto& f : files) {
        const std::string what = "experiment file " + f.file;
        Require(tables.insert(f.table).second, what, "table",
                "names table '" + f.table + "', which another file of this run fills too");
        for (const auto& e : f.experiments) {
            const auto [it, fresh] = ids.emplace(e.id, f.file);
            Require(fresh, what, "experiments", "repeats id '" + e.id + "' of " + it->second);
        }
    }
    for (const auto& f : files) {
        for (const auto& [key, id] :
             {std::pair{"timing_of", f.timing_of}, {"variants.pairs_of", f.variants.pairs_of}}) {
            Require(id.empty() || ids.count(id) > 0, "experiment file " + f.file, key,
                    "names experiment '" + id + "', which no file of this run has");
        }
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
