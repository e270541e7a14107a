// `regbench import-checkpoint` / `export-checkpoint`: the DeepGMR and OGMM authors' PyTorch
// state dicts (.pth, zip or legacy format) to and from regbench checkpoint folders
// (ogmm/authors_checkpoint.hpp).
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "app/cli_numbers.hpp"
#include "app/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/input_file.hpp"
#include "core/output_rule.hpp"
#include "core/sha256.hpp"
#ifdef REGBENCH_HAVE_LEARNED
#include "ogmm/authors_checkpoint.hpp"
#include "ogmm/checkpoint.hpp"
#include "ogmm/family.hpp"
#endif

namespace regbench::app {
namespace {

#ifdef REGBENCH_HAVE_LEARNED
struct ImportArgs {
    std::string file;
    std::string out;
    bool force = false;
    ogmm::ImportOptions options;
};

/// The network families with an authors' checkpoint format (ogmm/family.hpp), "a | b".
std::string Formats() {
    std::string list;
    for (const auto& f : ogmm::AuthorsFormats()) list += (list.empty() ? "" : " | ") + f;
    return list;
}

void SetupImport(CLI::App* cmd) {
    auto a = std::make_shared<ImportArgs>();
    cmd->add_option("FILE", a->file, "The authors' torch.save state dict (.pth; zip or legacy)")
        ->required();
    cmd->add_option("--from", a->options.from, "Whose module saved it: " + Formats())
        ->required()
        ->check(CLI::IsMember(ogmm::AuthorsFormats()));
    cmd->add_option("--out", a->out, "Checkpoint folder to write")->required();
    cmd->add_flag("--force", a->force,
                  "Replace an existing --out checkpoint folder (never another folder: a "
                  "training run's, or one holding other files, is refused)");
    cmd->add_option("--rri-variant", a->options.rri_variant,
                    "DeepGMR RRI orientation at run time: cuda (GPU kernel; the released models) "
                    "| numpy (CPU fallback of the authors' test.py)")
        ->capture_default_str()
        ->check(CLI::IsMember({"cuda", "numpy"}));
    cmd->add_option("--clusters", a->options.ogmm_clusters,
                    "OGMM: GMM components J (n_clusters; no tensor fixes it)")
        ->capture_default_str()
        ->check(PositiveWholeNumber());
    cmd->add_option("--anchors", a->options.ogmm_anchors, "OGMM: attention anchors (km_clusters)")
        ->capture_default_str()
        ->check(PositiveWholeNumber());
    cmd->add_option("--heads", a->options.ogmm_heads, "OGMM: attention heads (num_heads)")
        ->capture_default_str()
        ->check(PositiveWholeNumber());
    cmd->add_option("--k", a->options.ogmm_k, "OGMM: DGCNN neighbours (gnn_k)")
        ->capture_default_str()
        ->check(PositiveWholeNumber());
    cmd->callback([a] {
        // A folder, a FIFO or a device is named as such, not as "no such file".
        RequireRegularFile(a->file);
        // The one output rule (docs/usage.md, "Outputs"): `--out m.pth` given the input m.pth,
        // or an existing training run folder, replaced them; one writer per checkpoint folder.
        OutputRule rule;
        rule.replace = a->force;
        rule.folder = true;
        const ClaimedOutput claim(a->out, {a->file}, rule);
        // Refused before the import's work; the save checks again.
        if (a->force) ogmm::RequireReplaceableCheckpointFolder(a->out);
        const nlohmann::json j = ogmm::ImportAuthorsCheckpoint(a->file, a->out, a->options);
        std::cout << "import-checkpoint: wrote " << a->out << " ("
                  << j.at("config").at("name").get<std::string>() << ", " << j.at("mapping").size()
                  << " tensors from a " << j.at("imported_from").at("format").get<std::string>()
                  << " file, sha256 " << j.at("imported_from").at("sha256").get<std::string>()
                  << ")\n"
                  << "  config: " << j.at("model_config").dump() << "\n";
    });
}

struct ExportArgs {
    std::string dir;
    std::string to;
    std::string out;
    bool force = false;
};

void SetupExport(CLI::App* cmd) {
    auto a = std::make_shared<ExportArgs>();
    cmd->add_option("DIR", a->dir, "regbench checkpoint folder")->required();
    cmd->add_option("--to", a->to, "Whose module will load it: " + Formats())
        ->required()
        ->check(CLI::IsMember(ogmm::AuthorsFormats()));
    cmd->add_option("--out", a->out, ".pth file to write (zip format, torch.load-able)")
        ->required();
    cmd->add_flag("--force", a->force, "Replace an existing --out");
    cmd->callback([a] {
        const ClaimedOutput claim(a->out, {a->dir}, OutputRule{a->force});
        const ogmm::AuthorsPth pth = ogmm::ExportAuthorsPth(a->dir, a->to);
        WriteFileAtomic(a->out, pth.bytes,
                        {(std::filesystem::path(a->dir) / "weights.pt").string(),
                         (std::filesystem::path(a->dir) / "checkpoint.json").string()});
        std::cout << "export-checkpoint: wrote " << a->out << " (" << pth.tensors
                  << " tensors, sha256 " << Sha256File(a->out) << ")\n";
    });
}
#else
void SetupImport(CLI::App* cmd) {
    cmd->callback(
        [] { throw std::runtime_error("import-checkpoint: this build has no LibTorch"); });
}
void SetupExport(CLI::App* cmd) {
    cmd->callback(
        [] { throw std::runtime_error("export-checkpoint: this build has no LibTorch"); });
}
#endif

[[maybe_unused]] const bool kImportRegistered = RegisterCommand(
    {"import-checkpoint",
     "Import the DeepGMR / OGMM authors' PyTorch weights (.pth) as a checkpoint folder",
     SetupImport});
[[maybe_unused]] const bool kExportRegistered = RegisterCommand(
    {"export-checkpoint",
     "Export a checkpoint folder as a .pth the DeepGMR / OGMM authors' code loads", SetupExport});
}  // namespace

}  // namespace regbench::app
