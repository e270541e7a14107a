#include "networks/checkpoint/checkpoint.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>

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
#include "networks/checkpoint/checkpoint_json.hpp"
#include "networks/checkpoint/torch_save_reader.hpp"
#include "networks/family.hpp"
#include "networks/net.hpp"
#include "networks/zoo.hpp"

namespace regbench::networks {
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

namespace {

/// What a checkpoint folder holds; a folder holding anything else is never replaced or removed.
constexpr const char* kCheckpointEntries[] = {kCheckpointJson, kWeightsFile, kOptimizerFile};

/// The test hook of the kill-at-every-step tests: with REGBENCH_TEST_KILL_SAVE_AT=k in the
/// environment, SaveCheckpoint kills its own process (SIGKILL: no cleanup runs) right after
/// step k, as `kill -9` at that moment would.
void KillPoint(int step) {
    const char* at = std::getenv("REGBENCH_TEST_KILL_SAVE_AT");
    if (at != nullptr && std::atoi(at) == step) ::raise(SIGKILL);
}

/// fsync of a folder makes the renames and creations in it durable (POSIX leaves it to us).
void SyncFolder(const fs::path& dir) {
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return;  // some filesystems refuse; the rename has still happened
    ::fsync(fd);
    ::close(fd);
}

fs::path ParentOf(const fs::path& dir) {
    return dir.has_parent_path() ? dir.parent_path() : fs::path(".");
}

bool Present(const fs::path& p) {
    std::error_code ec;
    return fs::exists(fs::symlink_status(p, ec));
}

/// "dir/" and "dir" name the same folder: its temporaries are "dir.tmp" and "dir.old" beside it.
std::string WithoutTrailingSlashes(std::string dir) {
    while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
    return dir;
}

/// A whole checkpoint: its checkpoint.json parses (it is written last) and its weights file has
/// the recorded size and a whole zip archive.
bool IsCompleteCheckpoint(const fs::path& dir) {
    try {
        (void)ReadCheckpointJson(dir.string());
        return true;
    } catch (const std::exception&) {
        return false;
    }
}

}  // namespace

std::string WeightValueProblem(const torch::Tensor& t) {
    if (!t.is_floating_point() || t.numel() == 0) return "";
    const torch::Tensor d = t.detach().to(torch::kCPU, torch::kDouble);
    if (torch::isnan(d).any().item<bool>()) return "holds NaN";
    if (torch::isinf(d).any().item<bool>()) return "holds Inf";
    const double largest = d.abs().max().item<double>();
    if (largest <= kMaxAbsWeight) return "";
    std::ostringstream o;
    o << "holds |w| = " << largest << ", beyond the bound " << kMaxAbsWeight;
    return o.str();
}

std::string CheckpointFolderPath(const std::string& dir) {
    const std::string d = WithoutTrailingSlashes(dir);
    const std::string last = fs::path(d).filename().string();
    if (d.empty() || d == "/" || last == "." || last == "..") {
        throw std::invalid_argument("checkpoint folder '" + dir +
                                    "' is not a folder of its own ('.', '..' or '/'); give the "
                                    "folder by its name, e.g. ../ck");
    }
    return d;
}

void RequireReplaceableCheckpointFolder(const std::string& dir) {
    const fs::path path(WithoutTrailingSlashes(dir));
    std::error_code ec;
    const fs::file_status st = fs::symlink_status(path, ec);
    if (!fs::exists(st)) return;
    if (fs::is_symlink(st)) {
        throw std::runtime_error(path.string() +
                                 ": is a symbolic link; a checkpoint folder is never replaced "
                                 "through a link");
    }
    if (!fs::is_directory(st)) {
        throw std::runtime_error(path.string() +
                                 ": exists and is not a folder; refusing to replace it");
    }
    for (const auto& entry : fs::directory_iterator(path)) {
        const std::string name = entry.path().filename().string();
        const bool known = std::find_if(std::begin(kCheckpointEntries),
                                        std::end(kCheckpointEntries), [&](const char* e) {
                                            return name == e;
                                        }) != std::end(kCheckpointEntries);
        if (!known || entry.symlink_status().type() == fs::file_type::directory) {
            throw std::runtime_error(
                path.string() + ": not a regbench checkpoint folder (it holds " + name +
                "; a checkpoint holds only checkpoint.json, weights.pt and optimizer.pt): "
                "refusing to replace or remove it; give another folder");
        }
    }
}

std::string RecoverCheckpointFolder(const std::string& dir_arg) {
    const fs::path dir(CheckpointFolderPath(dir_arg));
    const fs::path tmp = dir.string() + ".tmp";
    const fs::path old = dir.string() + ".old";
    if (!Present(tmp) && !Present(old)) return "";
    // Only folders a save made are renamed or removed.
    RequireReplaceableCheckpointFolder(tmp.string());
    RequireReplaceableCheckpointFolder(old.string());
    std::string done;
    const auto note = [&](const std::string& what) { done += (done.empty() ? "" : "; ") + what; };
    if (!Present(dir)) {
        // Killed before the new folder was renamed in: a whole new one wins, else the old one
        // comes back; a first save cut short left nothing loadable.
        if (Present(tmp) && IsCompleteCheckpoint(tmp)) {
            fs::rename(tmp, dir);
            note("finished an interrupted save: renamed the complete " + tmp.string() + " to " +
                 dir.string());
        } else if (Present(old)) {
            fs::rename(old, dir);
            note("undid an interrupted save: renamed " + old.string() + " back to " +
                 dir.string());
        }
        SyncFolder(ParentOf(dir));
    }
    if (Present(tmp)) {
        fs::remove_all(tmp);
        note("removed " + tmp.string() + ", an incomplete save");
    }
    if (Present(old)) {
        fs::remove_all(old);
        note("removed " + old.string() + ", the checkpoint a finished save replaced");
    }
    return done;
}

// The order of a save, each step a kill point (KillPoint): (1-4) write DIR.tmp whole (folder,
// weights, optimizer state, then checkpoint.json: a parsable json means a whole folder), (5)
// rename DIR to DIR.old, (6) rename DIR.tmp to DIR, (7) remove DIR.old. A kill at any step
// leaves DIR whole, or DIR missing and a whole DIR.tmp or DIR.old that RecoverCheckpointFolder
// (the next save, train --resume) renames back; a loader names them (ReadCheckpointJson).
void SaveCheckpoint(const std::string& dir, RegistrationNet& net, const nlohmann::json& meta,
                    torch::optim::Optimizer* optimizer) {
    const fs::path final_dir(CheckpointFolderPath(dir));
    const fs::path tmp = final_dir.string() + ".tmp";
    const fs::path old = final_dir.string() + ".old";
    bool writing = false;
    // A full disk or a file-size limit fails inside torch's writer (a c10::Error with a stack
    // dump) or ours: either way the half-written folder is removed and the error names the
    // checkpoint, and the previous checkpoint at `dir` stays as it was.
    const auto undo = [&] {
        std::error_code ec;
        if (!writing) return;
        if (!Present(final_dir) && Present(old)) fs::rename(old, final_dir, ec);
        fs::remove_all(tmp, ec);
    };
    try {
        (void)RecoverCheckpointFolder(final_dir.string());
        RequireReplaceableCheckpointFolder(final_dir.string());
        writing = true;
        SaveCheckpointInto(tmp, net, meta, optimizer);
        SyncFolder(tmp);
        const bool replacing = Present(final_dir);
        if (replacing) {
            fs::rename(final_dir, old);
            KillPoint(5);
        }
        fs::rename(tmp, final_dir);
        SyncFolder(ParentOf(final_dir));
        KillPoint(6);
        if (replacing) {
            fs::remove_all(old);
            KillPoint(7);
        }
    } catch (const c10::Error& e) {
        undo();
        throw std::runtime_error("cannot save checkpoint " + final_dir.string() + ": " +
                                 e.what_without_backtrace());
    } catch (const std::exception& e) {
        undo();
        throw std::runtime_error("cannot save checkpoint " + final_dir.string() + ": " + e.what());
    }
}

void SaveCheckpointInto(const fs::path& tmp, RegistrationNet& net, const nlohmann::json& meta,
                        torch::optim::Optimizer* optimizer) {
    fs::create_directories(tmp);
    KillPoint(1);
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
    KillPoint(2);
    if (optimizer != nullptr) {
        std::ostringstream bytes;
        torch::save(*optimizer, bytes);
        WriteFileChecked(tmp / kOptimizerFile, bytes.str());
    }
    KillPoint(3);
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
    KillPoint(4);
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
    if (!Present(dir)) {
        // A save killed between its renames: name what it left rather than "no such file".
        const std::string base = WithoutTrailingSlashes(dir);
        std::string left;
        for (const char* suffix : {".tmp", ".old"}) {
            if (Present(base + suffix)) left += (left.empty() ? "" : " and ") + base + suffix;
        }
        if (!left.empty()) {
            throw std::runtime_error("checkpoint folder " + base +
                                     " is missing, but an interrupted save left " + left +
                                     ": the next save to it (train --resume, import-checkpoint "
                                     "--force) recovers it, or rename the complete one to " +
                                     base);
        }
    }
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
        // Its records' declared sizes against the file and the reader's budget first:
        // LibTorch's reader allocates what a record declares.
        CheckTorchZipSizes(weights.string());
        torch::serialize::InputArchive archive;
        archive.load_from(weights.string(), device);
        net.load(archive);
    } catch (const c10::Error& e) {
        throw std::runtime_error(
            "checkpoint weights " + weights.string() +
            " are corrupt or do not fit the model: " + e.what_without_backtrace());
    }
    // Poisoned weights (NaN, Inf, |w| > kMaxAbsWeight) ran silently and gave the identity.
    for (const bool buffers : {false, true}) {
        for (const auto& item : buffers ? net.named_buffers() : net.named_parameters()) {
            const std::string problem = WeightValueProblem(item.value());
            if (!problem.empty()) {
                throw std::runtime_error("checkpoint weights " + weights.string() + ": tensor " +
                                         item.key() + " " + problem +
                                         "; refusing to run poisoned weights");
            }
        }
    }
    if (optimizer != nullptr) {
        const fs::path opt = fs::path(dir) / kOptimizerFile;
        try {
            if (fs::exists(opt)) CheckTorchZipSizes(opt.string());
            torch::load(*optimizer, opt.string(), device);
        } catch (const c10::Error& e) {
            throw std::runtime_error("optimizer state " + opt.string() +
                                     " is missing or corrupt: " + e.what_without_backtrace());
        }
    }
    return j;
}

/// Refuses an `inference` that is not an object of keys of `family.inference_params`.
void CheckInferenceKeys(const nlohmann::json& inference, const NetworkFamily& family) {
    if (!inference.is_object()) {
        throw std::invalid_argument("inference config overrides must be an object, got " +
                                    inference.dump());
    }
    std::vector<std::string> allowed;
    for (const auto& p : family.inference_params) allowed.push_back(p.key);
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

/// `build`'s result; its error (LibTorch's without the stack dump) rethrown as
/// std::runtime_error "checkpoint file <dir>/checkpoint.json: cannot build its model: ...".
template <class Build>
auto BuildingCheckpointModel(const std::string& dir, Build build) -> decltype(build()) {
    try {
        return build();
    } catch (const c10::Error& e) {
        throw std::runtime_error("checkpoint file " + (fs::path(dir) / kCheckpointJson).string() +
                                 ": cannot build its model: " + e.what_without_backtrace());
    } catch (const std::exception& e) {
        throw std::runtime_error("checkpoint file " + (fs::path(dir) / kCheckpointJson).string() +
                                 ": cannot build its model: " + e.what());
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
    return BuildingCheckpointModel(dir, [&] {
        const NetworkFamily& family = FamilyOfConfig(config);
        nlohmann::json net = config;
        net.erase("train");
        family.check_config(net);
        return family.arch;
    });
}

std::shared_ptr<RegistrationNet> LoadNetFromCheckpoint(const std::string& dir,
                                                       const nlohmann::json& inference) {
    const nlohmann::json config = CheckpointNetConfig(dir, inference);
    const std::shared_ptr<RegistrationNet> net =
        BuildingCheckpointModel(dir, [&] { return MakeNetFromConfig(config); });
    LoadCheckpointAs(dir, *net, nullptr, inference);
    net->eval();
    return net;
}

}  // namespace regbench::networks
