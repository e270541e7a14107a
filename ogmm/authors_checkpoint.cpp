#include "ogmm/authors_checkpoint.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "ogmm/authors_state_dict.hpp"
#include "ogmm/checkpoint.hpp"
#include "ogmm/net.hpp"
#include "ogmm/rri.hpp"
#include "ogmm/zoo.hpp"

namespace regbench::ogmm {
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

/// regbench OGMM name prefix -> the authors' GMMReg name prefix. CONV(used='proj') is
/// net.{0 conv, 1 bn, 3 conv, 4 bn, 6 conv}; CONV(used=None) net.{0, 1, 3}.
const std::vector<std::pair<std::string, std::string>>& OgmmPrefixes() {
    static const std::vector<std::pair<std::string, std::string>> kPrefixes = [] {
        std::vector<std::pair<std::string, std::string>> v = {
            {"dgcnn.", "emd."},
            {"proj.conv1.", "proj.net.0."},
            {"proj.bn1.", "proj.net.1."},
            {"proj.conv2.", "proj.net.3."},
        };
        for (const auto& [rb, au] :
             std::vector<std::pair<std::string, std::string>>{{"conv3_o.", "overlap.net."},
                                                              {"conv3_a.", "conv1.net."},
                                                              {"conv3_b.", "conv2.net."}}) {
            v.emplace_back(rb + "conv1.", au + "0.");
            v.emplace_back(rb + "bn1.", au + "1.");
            v.emplace_back(rb + "conv2.", au + "3.");
            v.emplace_back(rb + "bn2.", au + "4.");
            v.emplace_back(rb + "conv3.", au + "6.");
        }
        v.emplace_back("spe.dist.", "pos.conv_dis.");
        v.emplace_back("spe.angle_2d.", "pos.conv_ang1.");
        v.emplace_back("spe.angle_1d.", "pos.conv_ang2.");
        v.emplace_back("spe.unused_conv.", "pos.conv.0.");
        v.emplace_back("spe.unused_bn.", "pos.conv.1.");
        for (const auto& [rb, au] : std::vector<std::pair<std::string, std::string>>{
                 {"att_s1.", "sattn1."}, {"att_c.", "cattn."}, {"att_s2.", "sattn2."}}) {
            v.emplace_back(rb + "merge.", au + "attn.merge.");
            v.emplace_back(rb + "proj.", au + "attn.proj.");
            v.emplace_back(rb + "mlp.", au + "mlp.");
        }
        return v;
    }();
    return kPrefixes;
}

/// The authors' GMMReg registers its modules in this order (its state_dict order).
int OgmmModuleRank(const std::string& authors_key) {
    static const char* kOrder[] = {"emd.", "proj.",   "overlap.", "conv1.", "conv2.",
                                   "pos.", "sattn1.", "cattn.",   "sattn2."};
    for (int j = 0; j < 9; ++j) {
        if (authors_key.rfind(kOrder[j], 0) == 0) return j;
    }
    return 9;
}

std::string OgmmAuthorsName(const std::string& rb) {
    for (const auto& [from, to] : OgmmPrefixes()) {
        if (rb.rfind(from, 0) == 0) return to + rb.substr(from.size());
    }
    throw std::logic_error("OGMM tensor " + rb + " has no counterpart in the authors' GMMReg");
}

const torch::Tensor* Find(const StateDict& sd, const std::string& key) {
    for (const auto& [k, v] : sd) {
        if (k == key) return &v;
    }
    return nullptr;
}

[[noreturn]] void Refuse(const std::string& file, const std::string& what) {
    throw std::runtime_error(file + ": " + what);
}

const torch::Tensor& Require(const StateDict& sd, const std::string& key, int64_t dims,
                             const std::string& file, const std::string& network) {
    const torch::Tensor* t = Find(sd, key);
    if (t == nullptr) {
        std::string first;
        for (size_t j = 0; j < sd.size() && j < 3; ++j) first += (j ? ", " : "") + sd[j].first;
        Refuse(file, "has no tensor " + key + ": not " + network + " state dict (its tensors are " +
                         first + (sd.size() > 3 ? ", ..." : "") + ")");
    }
    if (t->dim() != dims) {
        Refuse(file, "tensor " + key + " has shape " + ShapeString(t->sizes()) + ", expected " +
                         std::to_string(dims) + " dimensions");
    }
    return *t;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> AuthorsKeyMapping(const std::string& from,
                                                                   const nlohmann::json& config) {
    const auto net = MakeNetFromConfig(config);
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& [rb, tensor] : RegbenchTensors(*net)) {
        (void)tensor;
        out.emplace_back(from == "ogmm" ? OgmmAuthorsName(rb) : rb, rb);
    }
    if (from == "ogmm") {
        std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
            return OgmmModuleRank(a.first) < OgmmModuleRank(b.first);
        });
    }
    return out;
}

nlohmann::json InferAuthorsConfig(const StateDict& sd, const std::string& file,
                                  const ImportOptions& options) {
    if (options.from == "deepgmr") {
        for (const auto& [k, v] : sd) {
            (void)v;
            if (k.rfind("backbone.tnet.", 0) == 0) {
                Refuse(file, "tensor " + k +
                                 " belongs to DeepGMR's T-Net (--use_tnet), which "
                                 "regbench's deepgmr-orig does not have");
            }
        }
        const torch::Tensor& first =
            Require(sd, "backbone.encoder.0.0.weight", 3, file, "a DeepGMR");
        const int64_t d_in = first.size(1);
        nlohmann::json c;
        if (d_in == 3) {
            c = NamedConfig("deepgmr-orig-xyz");
        } else if (d_in >= 8 && d_in % 4 == 0) {
            c = NamedConfig("deepgmr-orig");
            c["rri_k"] = d_in / 4;
            c["rri_variant"] = ToString(ParseRriVariant(options.rri_variant));
        } else {
            Refuse(file, "tensor backbone.encoder.0.0.weight has " + std::to_string(d_in) +
                             " input channels: neither xyz (3) nor RRI (4k)");
        }
        c["d_model"] = Require(sd, "backbone.encoder.3.0.weight", 3, file, "DeepGMR").size(0);
        c["clusters"] = Require(sd, "backbone.decoder.3.weight", 3, file, "DeepGMR").size(0);
        return c;
    }
    if (options.from == "ogmm") {
        const torch::Tensor& conv5 = Require(sd, "emd.conv5.weight", 4, file, "an OGMM GMMReg");
        const int64_t emb = conv5.size(0);
        if (emb % 2 != 0 || emb % options.ogmm_heads != 0) {
            Refuse(file, "tensor emd.conv5.weight gives emb_dims " + std::to_string(emb) +
                             ", which is not even or not divisible by " +
                             std::to_string(options.ogmm_heads) + " heads");
        }
        nlohmann::json c = NamedConfig("ogmm");
        const bool authors_defaults = emb == 512 && options.ogmm_clusters == 128 &&
                                      options.ogmm_anchors == 128 && options.ogmm_heads == 4 &&
                                      options.ogmm_k == 20;
        c["name"] = authors_defaults ? "ogmm" : "ogmm-authors";
        c["emb_dims"] = emb;
        c["clusters"] = options.ogmm_clusters;
        c["anchors"] = options.ogmm_anchors;
        c["heads"] = options.ogmm_heads;
        c["k"] = options.ogmm_k;
        return c;
    }
    throw std::invalid_argument("--from must be deepgmr or ogmm, got '" + options.from + "'");
}

// Long on purpose: the import is one checked sequence (read, strip "module.", map every tensor,
// refuse leftovers, write, describe) whose steps each use what the previous one produced; the
// key mapping itself is AuthorsKeyMapping.
nlohmann::json ImportAuthorsCheckpoint(const std::string& pth, const std::string& out_dir,
                                       const ImportOptions& options) {
    if (options.from != "deepgmr" && options.from != "ogmm") {
        throw std::invalid_argument("--from must be deepgmr or ogmm, got '" + options.from + "'");
    }
    ParseRriVariant(options.rri_variant);
    TorchSaveContents contents = ReadTorchSaveFile(pth);
    StateDict& sd = contents.tensors;
    // nn.DataParallel saves every key under "module.".
    const bool data_parallel = std::all_of(
        sd.begin(), sd.end(), [](const auto& kv) { return kv.first.rfind("module.", 0) == 0; });
    if (data_parallel) {
        for (auto& kv : sd) kv.first = kv.first.substr(7);
    }
    const nlohmann::json config = InferAuthorsConfig(sd, pth, options);
    const auto net = MakeNetFromConfig(config);
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
        Refuse(pth, msg);
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
        {"sha256", Sha256File(pth)},
        {"bytes", fs::file_size(pth)},
        {"format", contents.format},
        {"from", options.from},
        {"module", options.from == "deepgmr" ? "DeepGMR (wentaoyuan/deepgmr model.py)"
                                             : "GMMReg (gfmei/ogmm models/gmmreg.py)"},
        {"wrapper_key", contents.wrapper},
        {"stripped_prefix", data_parallel ? "module." : ""},
        {"defaulted_to_zero", defaulted},
    };
    meta["mapping"] = map_json;
    SaveCheckpoint(out_dir, *net, meta);
    return ReadCheckpointJson(out_dir);
}

StateDict ExportAuthorsStateDict(const std::string& dir, const std::string& to) {
    if (to != "deepgmr" && to != "ogmm") {
        throw std::invalid_argument("--to must be deepgmr or ogmm, got '" + to + "'");
    }
    const nlohmann::json j = ReadCheckpointJson(dir);
    const nlohmann::json config = j.contains("config") ? j.at("config") : j.at("model_config");
    const std::string arch = config.value("arch", "");
    const std::string where = (fs::path(dir) / kCheckpointJson).string();
    if (arch != to) Refuse(where, "holds a " + arch + " model, not " + to);
    if (to == "deepgmr" && config.value("features", "") == "dgcnn") {
        Refuse(where,
               "holds the OGMM paper's DeepGMR variant (DGCNN features), which the "
               "DeepGMR authors' module cannot hold; only deepgmr-orig / -xyz export");
    }
    if (to == "ogmm" &&
        (!config.value("spe", true) || !config.value("csa", true) || !config.value("osp", true))) {
        Refuse(where,
               "holds an OGMM ablation (spe/csa/osp off) whose modules the authors' "
               "GMMReg does not match");
    }
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

}  // namespace regbench::ogmm
