#include "ogmm/checkpoint.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "core/atomic_file.hpp"
#include "core/input_file.hpp"
#include "core/version.hpp"
#include "ogmm/checkpoint_json.hpp"
#include "ogmm/family.hpp"
#include "ogmm/net.hpp"
#include "ogmm/zoo.hpp"

namespace regbench::ogmm {
namespace fs = std::filesystem;

namespace {
constexpr char kFormat[] = "regbench-checkpoint";
constexpr int kFormatVersion = 1;
}  // namespace

/// Creates `path` with `bytes`: every write, the fsync and the close checked (ENOSPC, EFBIG).
void WriteFileChecked(const fs::path& path, const std::string& bytes) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0)
        throw std::runtime_error(path.string() + ": cannot create: " + std::strerror(errno));
    try {
        WriteAllOrThrow(fd, bytes, path.string());
    } catch (...) {
        ::close(fd);
        throw;
    }
    const bool synced = ::fsync(fd) == 0;
    if (::close(fd) != 0 || !synced) {
        throw std::runtime_error(path.string() + ": write failed: " + std::strerror(errno));
    }
}

/// Writes the weights, optimizer state and checkpoint.json into the folder `tmp`.
void SaveCheckpointInto(const fs::path& tmp, RegistrationNet& net, const nlohmann::json& meta,
                        torch::optim::Optimizer* optimizer);

std::string BuildVersion() { return RegbenchVersion(); }
std::string BuildGitSha() { return RegbenchGitSha(); }

void SaveCheckpoint(const std::string& dir, RegistrationNet& net, const nlohmann::json& meta,
                    torch::optim::Optimizer* optimizer) {
    const fs::path final_dir(dir);
    const fs::path tmp = final_dir.string() + ".tmp";
    // A full disk or a file-size limit fails inside torch's writer (a c10::Error with a stack
    // dump) or ours: either way the half-written folder is removed and the error names the
    // checkpoint, and the previous checkpoint at `dir` stays as it was.
    try {
        SaveCheckpointInto(tmp, net, meta, optimizer);
        fs::remove_all(final_dir);
        fs::rename(tmp, final_dir);
    } catch (const c10::Error& e) {
        std::error_code ec;
        fs::remove_all(tmp, ec);
        throw std::runtime_error("cannot save checkpoint " + final_dir.string() + ": " +
                                 e.what_without_backtrace());
    } catch (const std::exception& e) {
        std::error_code ec;
        fs::remove_all(tmp, ec);
        throw std::runtime_error("cannot save checkpoint " + final_dir.string() + ": " + e.what());
    }
}

void SaveCheckpointInto(const fs::path& tmp, RegistrationNet& net, const nlohmann::json& meta,
                        torch::optim::Optimizer* optimizer) {
    fs::remove_all(tmp);
    fs::create_directories(tmp);
    // torch's file writer throws on a failed write and then throws again from its destructor
    // (std::terminate, a c10 stack dump): serialise into memory, where nothing fails, and write
    // the bytes with checked writes.
    {
        torch::serialize::OutputArchive archive;
        net.save(archive);
        std::ostringstream bytes;
        archive.save_to(bytes);
        WriteFileChecked(tmp / kWeightsFile, bytes.str());
    }
    if (optimizer != nullptr) {
        std::ostringstream bytes;
        torch::save(*optimizer, bytes);
        WriteFileChecked(tmp / kOptimizerFile, bytes.str());
    }
    nlohmann::json j = meta;
    j["format"] = kFormat;
    j["format_version"] = kFormatVersion;
    j["model_config"] = net.Config();
    j["regbench_version"] = BuildVersion();
    j["git_sha"] = BuildGitSha();
    j["weights"] = kWeightsFile;
    j["weights_bytes"] = fs::file_size(tmp / kWeightsFile);
    WriteFileChecked(tmp / kCheckpointJson,
                     j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

namespace {

/// The weights file's size, first bytes and last bytes, for CheckWeightsBytes: never the whole
/// file (megabytes) at method creation. A missing file, a link to a device or a FIFO is refused
/// by name.
void CheckWeightsFile(const fs::path& path, const nlohmann::json& checkpoint) {
    if (!fs::exists(fs::symlink_status(path))) {
        throw std::runtime_error("weights file " + path.string() + " is missing");
    }
    RequireRegularFile(path.string());
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("weights file " + path.string() + " cannot be opened");
    const std::uint64_t size = fs::file_size(path);
    std::string head(static_cast<std::size_t>(std::min<std::uint64_t>(size, 4)), '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    const std::uint64_t tail_size = std::min<std::uint64_t>(size, kWeightsTailBytes);
    std::string tail(static_cast<std::size_t>(tail_size), '\0');
    in.seekg(static_cast<std::streamoff>(size - tail_size));
    in.read(tail.data(), static_cast<std::streamsize>(tail.size()));
    if (!in) throw std::runtime_error("weights file " + path.string() + " cannot be read");
    CheckWeightsBytes(head, tail, size, checkpoint, path.string());
}

}  // namespace

nlohmann::json ReadCheckpointJson(const std::string& dir) {
    const fs::path path = fs::path(dir) / kCheckpointJson;
    RequireRegularFile(path.string());
    std::ifstream in(path);
    if (!in) throw std::runtime_error("checkpoint file " + path.string() + " cannot be opened");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    nlohmann::json j = ParseCheckpointJson(text, path.string());  // torch-free (fuzzed)
    CheckWeightsFile(fs::path(dir) / kWeightsFile, j);
    return j;
}

namespace {

/// LoadCheckpoint with the model_config the net must have: the checkpoint's, with `inference`
/// merged over it.
nlohmann::json LoadCheckpointAs(const std::string& dir, RegistrationNet& net,
                                torch::optim::Optimizer* optimizer,
                                const nlohmann::json& inference) {
    const nlohmann::json j = ReadCheckpointJson(dir);
    const fs::path json_path = fs::path(dir) / kCheckpointJson;
    nlohmann::json expected = j.at("model_config");
    if (expected.is_object()) {
        for (const auto& [key, value] : inference.items()) expected[key] = value;
    }
    if (expected != net.Config()) {
        throw std::runtime_error("checkpoint file " + json_path.string() +
                                 " was saved from another model config: " + expected.dump() +
                                 " vs " + net.Config().dump());
    }
    const fs::path weights = fs::path(dir) / kWeightsFile;
    // Tensors load onto the device the net is on, whichever device saved them: a checkpoint
    // trained on a GPU resumes and runs on a CPU-only build, and the other way round.
    const auto params = net.parameters();
    const torch::Device device = params.empty() ? torch::Device(torch::kCPU) : params[0].device();
    try {
        torch::serialize::InputArchive archive;
        archive.load_from(weights.string(), device);
        net.load(archive);
    } catch (const c10::Error& e) {
        throw std::runtime_error(
            "checkpoint weights " + weights.string() +
            " are corrupt or do not fit the model: " + e.what_without_backtrace());
    }
    if (optimizer != nullptr) {
        const fs::path opt = fs::path(dir) / kOptimizerFile;
        try {
            torch::load(*optimizer, opt.string(), device);
        } catch (const c10::Error& e) {
            throw std::runtime_error("optimizer state " + opt.string() +
                                     " is missing or corrupt: " + e.what_without_backtrace());
        }
    }
    return j;
}

/// Refuses an `inference` that is not an object of keys of `family.inference_keys`.
void CheckInferenceKeys(const nlohmann::json& inference, const NetworkFamily& family) {
    if (!inference.is_object()) {
        throw std::invalid_argument("inference config overrides must be an object, got " +
                                    inference.dump());
    }
    const auto& allowed = family.inference_keys;
    for (const auto& [key, value] : inference.items()) {
        (void)value;
        if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
            std::string may;
            for (const auto& k : allowed) may += (may.empty() ? "\"" : ", \"") + k + "\"";
            throw std::invalid_argument(
                "config key '" + key + "' changes the network's parameters; only " +
                (may.empty() ? std::string("no key") : may) + " may differ from the checkpoint's");
        }
    }
}

}  // namespace

nlohmann::json LoadCheckpoint(const std::string& dir, RegistrationNet& net,
                              torch::optim::Optimizer* optimizer) {
    return LoadCheckpointAs(dir, net, optimizer, nlohmann::json::object());
}

nlohmann::json CheckpointNetConfig(const std::string& dir, const nlohmann::json& inference) {
    const nlohmann::json j = ReadCheckpointJson(dir);
    // "config" (the zoo config, with "arch") builds it; model_config is what it must equal.
    nlohmann::json config = j.contains("config") ? j.at("config") : j.at("model_config");
    CheckInferenceKeys(inference, FamilyOfConfig(config));
    for (const auto& [key, value] : inference.items()) config[key] = value;
    return config;
}

std::string CheckCheckpointModel(const std::string& dir, const nlohmann::json& inference) {
    const nlohmann::json config = CheckpointNetConfig(dir, inference);
    try {
        const NetworkFamily& family = FamilyOfConfig(config);
        nlohmann::json net = config;
        net.erase("train");
        family.check_config(net);
        return family.arch;
    } catch (const std::exception& e) {
        throw std::runtime_error("checkpoint file " + (fs::path(dir) / kCheckpointJson).string() +
                                 ": cannot build its model: " + e.what());
    }
}

std::shared_ptr<RegistrationNet> LoadNetFromCheckpoint(const std::string& dir,
                                                       const nlohmann::json& inference) {
    const nlohmann::json config = CheckpointNetConfig(dir, inference);
    std::shared_ptr<RegistrationNet> net;
    try {
        net = MakeNetFromConfig(config);
    } catch (const std::exception& e) {
        throw std::runtime_error("checkpoint file " + (fs::path(dir) / kCheckpointJson).string() +
                                 ": cannot build its model: " + e.what());
    }
    LoadCheckpointAs(dir, *net, nullptr, inference);
    net->eval();
    return net;
}

}  // namespace regbench::ogmm
