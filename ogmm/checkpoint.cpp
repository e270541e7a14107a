#include "ogmm/checkpoint.hpp"

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "core/version.hpp"
#include "ogmm/zoo.hpp"

namespace regbench::ogmm {
namespace fs = std::filesystem;

namespace {
constexpr char kFormat[] = "regbench-checkpoint";
constexpr int kFormatVersion = 1;
}  // namespace

std::string BuildVersion() { return RegbenchVersion(); }
std::string BuildGitSha() { return RegbenchGitSha(); }

void SaveCheckpoint(const std::string& dir,
                    RegistrationNet& net,
                    const nlohmann::json& meta,
                    torch::optim::Optimizer* optimizer) {
    const fs::path final_dir(dir);
    const fs::path tmp = final_dir.string() + ".tmp";
    fs::remove_all(tmp);
    fs::create_directories(tmp);
    {
        torch::serialize::OutputArchive archive;
        net.save(archive);
        archive.save_to((tmp / kWeightsFile).string());
    }
    if (optimizer != nullptr) torch::save(*optimizer, (tmp / kOptimizerFile).string());
    nlohmann::json j = meta;
    j["format"] = kFormat;
    j["format_version"] = kFormatVersion;
    j["model_config"] = net.Config();
    j["regbench_version"] = BuildVersion();
    j["git_sha"] = BuildGitSha();
    j["weights"] = kWeightsFile;
    j["weights_bytes"] = fs::file_size(tmp / kWeightsFile);
    {
        std::ofstream out(tmp / kCheckpointJson);
        out << j.dump(2) << "\n";
        if (!out) throw std::runtime_error("cannot write " + (tmp / kCheckpointJson).string());
    }
    fs::remove_all(final_dir);
    fs::rename(tmp, final_dir);
}

nlohmann::json ReadCheckpointJson(const std::string& dir) {
    const fs::path path = fs::path(dir) / kCheckpointJson;
    std::ifstream in(path);
    if (!in) throw std::runtime_error("checkpoint file " + path.string() + " cannot be opened");
    nlohmann::json j;
    try {
        in >> j;
    } catch (const std::exception& e) {
        throw std::runtime_error("checkpoint file " + path.string() +
                                 " is not valid JSON: " + e.what());
    }
    if (!j.is_object() || j.value("format", "") != kFormat || !j.contains("model_config")) {
        throw std::runtime_error("checkpoint file " + path.string() +
                                 " is not a regbench checkpoint (no format/model_config)");
    }
    return j;
}

nlohmann::json LoadCheckpoint(const std::string& dir,
                              RegistrationNet& net,
                              torch::optim::Optimizer* optimizer) {
    const nlohmann::json j = ReadCheckpointJson(dir);
    const fs::path json_path = fs::path(dir) / kCheckpointJson;
    if (j.at("model_config") != net.Config()) {
        throw std::runtime_error("checkpoint file " + json_path.string() +
                                 " was saved from another model config: " +
                                 j.at("model_config").dump() + " vs " + net.Config().dump());
    }
    const fs::path weights = fs::path(dir) / kWeightsFile;
    try {
        torch::serialize::InputArchive archive;
        archive.load_from(weights.string());
        net.load(archive);
    } catch (const c10::Error& e) {
        throw std::runtime_error(
            "checkpoint weights " + weights.string() +
            " are corrupt or do not fit the model: " + e.what_without_backtrace());
    }
    if (optimizer != nullptr) {
        const fs::path opt = fs::path(dir) / kOptimizerFile;
        try {
            torch::load(*optimizer, opt.string());
        } catch (const c10::Error& e) {
            throw std::runtime_error("optimizer state " + opt.string() +
                                     " is missing or corrupt: " + e.what_without_backtrace());
        }
    }
    return j;
}

std::shared_ptr<RegistrationNet> LoadNetFromCheckpoint(const std::string& dir) {
    const nlohmann::json j = ReadCheckpointJson(dir);
    std::shared_ptr<RegistrationNet> net;
    try {
        // "config" (the zoo config, with "arch") builds it; model_config is what it must equal.
        net = MakeNetFromConfig(j.contains("config") ? j.at("config") : j.at("model_config"));
    } catch (const std::exception& e) {
        throw std::runtime_error("checkpoint file " + (fs::path(dir) / kCheckpointJson).string() +
                                 ": cannot build its model: " + e.what());
    }
    LoadCheckpoint(dir, *net);
    net->eval();
    return net;
}

}  // namespace regbench::ogmm
