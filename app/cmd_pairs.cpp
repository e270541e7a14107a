// `regbench inspect`, `regbench export`, `regbench import`: look into and convert pair files;
// `inspect` also summarises a checkpoint folder.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include "app/cli_numbers.hpp"
#include "app/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/output_rule.hpp"
#include "core/version.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_hash.hpp"
#include "protocols/pair_protocols.hpp"
#include "protocols/pair_summary.hpp"
#include "protocols/xyz_io.hpp"

namespace regbench::app {

namespace {

/// What `inspect DIR` shows of a checkpoint folder's checkpoint.json: the model and its
/// config, how it was made (training steps and data, or the authors' file it was imported
/// from, with the preset and the import settings no tensor fixed, and which were assumed).
nlohmann::json CheckpointSummary(const std::string& dir) {
    const std::string path = (std::filesystem::path(dir) / "checkpoint.json").string();
    std::ifstream in(path);
    nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    if (!in || j.is_discarded() || !j.is_object()) {
        throw std::runtime_error(path + ": not a readable checkpoint.json (JSON object)");
    }
    nlohmann::json out = {{"checkpoint", dir}};
    for (const char* key : {"model", "steps", "pairs_seen", "data", "worse_than_identity",
                            "imported_from", "model_config"}) {
        if (j.contains(key)) out[key] = j[key];
    }
    if (!out.contains("model_config") && j.contains("config")) out["model_config"] = j["config"];
    return out;
}

void SetupInspectCommand(CLI::App* cmd) {
    auto file = std::make_shared<std::string>();
    auto json_out = std::make_shared<bool>(false);
    cmd->add_option("file", *file, "Pair file (.h5), or a checkpoint folder")->required();
    cmd->add_flag("--json", *json_out, "Print as JSON");
    cmd->callback([file, json_out] {
        if (std::filesystem::is_directory(*file)) {
            const nlohmann::json c = CheckpointSummary(*file);
            if (*json_out) {
                std::cout << c.dump(2) << "\n";
                return;
            }
            std::cout << "checkpoint: " << *file << "\n";
            for (const auto& [key, value] : c.items()) {
                if (key == "checkpoint") continue;
                std::cout << key << ": "
                          << (value.is_string() ? value.get<std::string>() : value.dump()) << "\n";
            }
            return;
        }
        const PairSet set = ReadPairFile(*file);
        const PairSetSummary summary = SummarizePairSet(set);
        if (*json_out) {
            std::cout << nlohmann::json{{"file", *file},
                                        {"summary", ToJson(summary)},
                                        {"provenance", set.provenance}}
                             // A path or provenance of any bytes (not UTF-8) is printed
                             // with U+FFFD, not refused by a raw type_error.316.
                             .dump(2, ' ', false, nlohmann::json::error_handler_t::replace)
                      << "\n";
            return;
        }
        std::cout << "file: " << *file << "\n"
                  << FormatSummary(summary) << "provenance:\n"
                  << set.provenance.dump(2, ' ', false, nlohmann::json::error_handler_t::replace)
                  << "\n";
    });
}

void SetupExportCommand(CLI::App* cmd) {
    auto file = std::make_shared<std::string>();
    auto dir = std::make_shared<std::string>();
    auto format = std::make_shared<std::string>("xyz");
    cmd->add_option("file", *file, "Pair file (.h5)")->required();
    cmd->add_option("--out", *dir, "Output directory")->required();
    cmd->add_option("--format", *format, "xyz | ply")
        ->check(CLI::IsMember({"xyz", "ply"}))
        ->capture_default_str();
    cmd->callback([file, dir, format] {
        // The one output rule (docs/usage.md, "Outputs"); one export into a folder at a time.
        // An existing empty folder is fine, a non-empty one is refused by the exporter.
        OutputRule rule;
        rule.folder = true;
        rule.continues = true;
        const ClaimedOutput claim(*dir, {*file}, rule);
        const PairSet set = ReadPairFile(*file);
        if (*format == "ply") {
            ExportPly(set, *dir);
        } else {
            ExportXyz(set, *dir);
        }
        // The pairs' content hash, for transforms files computed on these pairs: `score`
        // refuses transforms that record another pair file's hash.
        const std::string hash = PairSetContentHash(set);
        const std::string hash_path = (std::filesystem::path(*dir) / "content_hash.txt").string();
        WriteFileAtomic(hash_path, hash + "\n", {*file});
        std::cerr << "export: wrote " << set.pairs.size() << " pairs to " << *dir
                  << " (content hash " << hash << " in " << hash_path
                  << ": record it in transforms files as \"content_hash\" or a "
                     "\"# content_hash: ...\" line)\n";
    });
}

void SetupImportCommand(CLI::App* cmd) {
    auto dir = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto eta = std::make_shared<double>(ProtocolOptions{}.eta);
    auto force = std::make_shared<bool>(false);
    cmd->add_option("--xyz-dir", *dir, "Directory with the xyz layout")->required();
    cmd->add_option("--out", *out, "Output HDF5 file")->required();
    cmd->add_option("--eta", *eta, "Overlap label radius")
        ->check(PositiveReal())  // nan, inf, 1e400, -1, 0 and '' were accepted or failed late
        ->capture_default_str();
    cmd->add_flag("--force", *force, "Replace an existing --out");
    cmd->callback([dir, out, eta, force] {
        // The one output rule (docs/usage.md, "Outputs"): --out may not lie inside the folder
        // being imported nor be a hard link to any file of it (compared by device and inode).
        std::vector<std::string> inputs{*dir};
        std::error_code ec;
        for (const auto& e : std::filesystem::recursive_directory_iterator(*dir, ec)) {
            if (e.is_regular_file(ec)) inputs.push_back(e.path().string());
        }
        const ClaimedOutput claim(*out, inputs, OutputRule{*force});
        PairSet set = ImportXyzDir(*dir, *eta);
        set.provenance["regbench_version"] = RegbenchVersion();
        set.provenance["git_sha"] = RegbenchGitSha();
        set.provenance["content_hash"] = PairSetContentHash(set);
        WritePairFile(*out, set);
        std::cerr << "import: wrote " << set.pairs.size() << " pairs to " << *out << "\n";
    });
}

[[maybe_unused]] const bool kInspectRegistered =
    RegisterCommand({"inspect",
                     "Summarise a pair file (counts, overlap, motions, CCD floor) or a "
                     "checkpoint folder (model, config, training or import settings)",
                     SetupInspectCommand});
[[maybe_unused]] const bool kExportRegistered = RegisterCommand(
    {"export", "Write a pair file's pairs as xyz or PLY files", SetupExportCommand});
[[maybe_unused]] const bool kImportRegistered = RegisterCommand(
    {"import", "Build a pair file from NNNN_{src,tgt}.xyz + NNNN_gt.txt", SetupImportCommand});
}  // namespace

}  // namespace regbench::app
