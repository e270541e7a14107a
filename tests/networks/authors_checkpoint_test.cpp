// The authors' checkpoints in regbench (issue 23): files written at test time by Debian's
// python3-torch (tests/networks/authors_parity.py, both torch.save formats) are imported and run;
// every expected value comes from that script: its own PyTorch forward of the authors' DeepGMR
// and, for OGMM, scripts/ogmm_reference.py's forward on the authors'-layout weights, the files'
// sha256 from Python's hashlib, and the round trip's equality from torch.load + torch.equal +
// load_state_dict(strict=True) in the authors' layout. Skipped (with the reason) where
// /usr/bin/python3 has no torch.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "networks/checkpoint/authors_checkpoint.hpp"
#include "networks/checkpoint/authors_format.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/layers/gmm_head.hpp"
#include "networks/net.hpp"
#include "networks/checkpoint/torch_save_reader.hpp"
#include "tests/networks/state_fixture.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/shell.hpp"

namespace regbench::networks {
namespace {
namespace fs = std::filesystem;

using testing::ErrorOf;

std::string SourceDir() {
    const char* env = std::getenv("REGBENCH_SOURCE_DIR");
    return env != nullptr ? env : ".";
}

const std::string kPython = "/usr/bin/python3";

class AuthorsCheckpoint : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        torch::set_num_threads(1);
        if (regbench::testing::RunShell(kPython + " -c 'import torch' 2>/dev/null").exit_code !=
            0) {
            missing_ = kPython +
                       " cannot import torch (scripts/install_deps.sh installs "
                       "python3-torch); the parity fixtures are written by it";
            return;
        }
        dir_ = new fs::path(testing::FreshTempDir("authors_ckpt"));
        const auto [rc, out] = regbench::testing::RunShell(kPython + " " + SourceDir() +
                                                           "/tests/networks/authors_parity.py make " +
                                                           dir_->string() + " 2>&1");
        ASSERT_EQ(rc, 0) << out;
        std::ifstream in(*dir_ / "reference.json");
        ref_ = new nlohmann::json(nlohmann::json::parse(in));
    }
    static void TearDownTestSuite() {
        if (dir_ != nullptr) fs::remove_all(*dir_);
        delete dir_;
        delete ref_;
        dir_ = nullptr;
        ref_ = nullptr;
    }
    void SetUp() override {
        // A missing reference fails: a skipped parity test would pass CI without checking.
        ASSERT_TRUE(missing_.empty()) << missing_;
    }
    static fs::path File(const std::string& name) { return *dir_ / name; }
    static const nlohmann::json& Ref() { return *ref_; }

    static inline fs::path* dir_ = nullptr;
    static inline nlohmann::json* ref_ = nullptr;
    static inline std::string missing_;
};

double MaxAbs(const torch::Tensor& a, const torch::Tensor& b) {
    return (a.to(torch::kDouble) - b.to(torch::kDouble)).abs().max().item<double>();
}

ImportOptions OptionsFor(const std::string& name) {
    ImportOptions o;
    if (name.rfind("ogmm", 0) == 0) {
        o.from = "ogmm";
        o.settings = {{"clusters", 8}, {"anchors", 16}, {"heads", 2}, {"k", 10}};
    } else {
        o.from = "deepgmr";
    }
    return o;
}

class AuthorsParity : public AuthorsCheckpoint,
                      public ::testing::WithParamInterface<std::tuple<std::string, std::string>> {};

// Import (both formats) and forward: transform within 1e-4, gamma / pi / mu of the source
// within 1e-5 of the Python forward on the same weights and pair (BatchNorm in eval mode with
// the non-trivial running statistics the script set).
TEST_P(AuthorsParity, ImportedForwardMatchesPyTorch) {
    const auto& [name, format] = GetParam();
    const fs::path pth = File(name + "_" + format + ".pth");
    const fs::path ck = File("ck_" + name + "_" + format);
    const nlohmann::json j = ImportAuthorsCheckpoint(pth.string(), ck.string(), OptionsFor(name));
    const nlohmann::json& r = Ref().at("cases").at(name);
    EXPECT_EQ(j.at("imported_from").at("sha256"), Ref().at("sha256").at(pth.filename().string()));
    EXPECT_EQ(j.at("imported_from").at("format"), format);
    EXPECT_EQ(j.at("mapping").size(), r.at("tensors").get<size_t>());

    const auto net = LoadNetFromCheckpoint(ck.string());
    torch::NoGradGuard no_grad;
    PairBatch batch;
    batch.source = TensorFromJson(Ref().at("source")).to(torch::kFloat).unsqueeze(0);
    batch.target = TensorFromJson(Ref().at("target")).to(torch::kFloat).unsqueeze(0);
    torch::manual_seed(Ref().at("ogmm_seed").get<uint64_t>());  // FPS starts, as the script
    const NetOutput out = net->Forward(batch);
    EXPECT_LT(MaxAbs(out.T[0], TensorFromJson(r.at("T"))), 1e-4);
    const torch::Tensor gamma = out.aux.at("gamma_source")[0];
    EXPECT_LT(MaxAbs(gamma, TensorFromJson(r.at("gamma"))), 1e-5);
    EXPECT_LT(MaxAbs(out.aux.at("pi_source")[0], TensorFromJson(r.at("pi"))), 1e-5);
    const torch::Tensor mu = out.aux.count("mu_source") != 0
                                 ? out.aux.at("mu_source")[0]
                                 : ComputeGmmParams(out.aux.at("gamma_source"), batch.source).mu[0];
    EXPECT_LT(MaxAbs(mu, TensorFromJson(r.at("mu"))), 1e-5);
    // The checks above must see a non-degenerate assignment.
    EXPECT_GT(gamma.max().item<double>(), 1.5 / static_cast<double>(gamma.size(1)));
}

INSTANTIATE_TEST_SUITE_P(
    All, AuthorsParity,
    ::testing::Combine(::testing::Values("deepgmr_rri", "deepgmr_xyz", "ogmm_small"),
                       ::testing::Values("legacy", "zip")),
    [](const auto& info) { return std::get<0>(info.param) + "_" + std::get<1>(info.param); });

// .pth -> import -> export -> .pth: bit-identical tensors, same keys in the same order, and the
// file loads strictly into the authors' module layout (checked by the Python script).
TEST_F(AuthorsCheckpoint, RoundTripIsBitIdenticalAndLoadsStrictly) {
    for (const std::string name : {"deepgmr_rri", "deepgmr_xyz", "ogmm_small"}) {
        for (const std::string format : {"legacy", "zip"}) {
            const fs::path pth = File(name + "_" + format + ".pth");
            const fs::path ck = File("rt_" + name + "_" + format);
            const ImportOptions o = OptionsFor(name);
            ImportAuthorsCheckpoint(pth.string(), ck.string(), o);
            const fs::path back = File("rt_" + name + "_" + format + ".pth");
            testing::WriteBytes(back,
                                WriteTorchSaveZip(ExportAuthorsStateDict(ck.string(), o.from)));
            const auto [rc, out] = regbench::testing::RunShell(
                kPython + " " + SourceDir() + "/tests/networks/authors_parity.py compare " +
                pth.string() + " " + back.string() + " " + o.from + " 2>&1");
            EXPECT_EQ(rc, 0) << name << " " << format << ": " << out;
            EXPECT_NE(out.find("identical"), std::string::npos) << out;
        }
    }
}

// Refusals name the file and never crash: another network's state dict, a random pickle, a
// TorchScript archive, truncated and corrupted files of both formats, and a state dict with a
// missing, an unexpected and a mis-shaped tensor (each named).
TEST_F(AuthorsCheckpoint, ForeignCorruptAndTruncatedFilesAreRefusedByName) {
    ImportOptions deepgmr;
    deepgmr.from = "deepgmr";
    const auto refused = [&](const fs::path& f, const ImportOptions& o) {
        const std::string e =
            ErrorOf([&] { ImportAuthorsCheckpoint(f.string(), File("refused").string(), o); });
        EXPECT_FALSE(fs::exists(File("refused"))) << f;
        return e;
    };
    for (const char* f : {"other_net.pth", "random.pickle", "torchscript.pth"}) {
        const std::string e = refused(File(f), deepgmr);
        EXPECT_NE(e.find(File(f).string()), std::string::npos) << e;
    }
    EXPECT_NE(refused(File("torchscript.pth"), deepgmr).find("TorchScript"), std::string::npos);
    EXPECT_NE(refused(File("ogmm_small_zip.pth"), deepgmr).find("not a DeepGMR"),
              std::string::npos);
    for (const char* f : {"deepgmr_xyz_legacy.pth", "deepgmr_xyz_zip.pth"}) {
        const std::string bytes = testing::ReadBytes(File(f));
        for (const size_t cut :
             {size_t{1}, size_t{20}, size_t{300}, bytes.size() / 2, bytes.size() - 9}) {
            const fs::path t = File(std::string("cut_") + f);
            testing::WriteBytes(t, bytes.substr(0, cut));
            const std::string e = refused(t, deepgmr);
            EXPECT_NE(e.find(t.string()), std::string::npos) << cut << ": " << e;
        }
        for (const size_t at : {size_t{2}, size_t{40}, size_t{200}, size_t{700}}) {
            std::string damaged = bytes;
            damaged[at] = static_cast<char>(damaged[at] ^ 0x5a);
            const fs::path t = File(std::string("bad_") + f);
            testing::WriteBytes(t, damaged);
            try {
                ImportAuthorsCheckpoint(t.string(), File("damaged").string(), deepgmr);
                fs::remove_all(File("damaged"));  // a flipped byte inside weights still imports
            } catch (const std::exception& e) {
                EXPECT_NE(std::string(e.what()).find(t.string()), std::string::npos) << e.what();
            }
        }
    }
    // Missing, unexpected and mis-shaped tensors, all named in one message.
    TorchSaveContents c = ReadTorchSaveFile(File("deepgmr_xyz_zip.pth").string());
    StateDict sd;
    for (auto& [k, v] : c.tensors) {
        if (k == "backbone.decoder.1.1.running_var") continue;
        if (k == "backbone.decoder.2.0.weight") v = torch::zeros({128, 255, 1});
        sd.emplace_back(k, v);
    }
    sd.emplace_back("backbone.extra.weight", torch::zeros({2}));
    const fs::path broken = File("broken.pth");
    testing::WriteBytes(broken, WriteTorchSaveZip(sd));
    const std::string e = refused(broken, deepgmr);
    EXPECT_NE(e.find(broken.string()), std::string::npos) << e;
    EXPECT_NE(e.find("missing tensor backbone.decoder.1.1.running_var"), std::string::npos) << e;
    EXPECT_NE(e.find("unexpected tensor backbone.extra.weight"), std::string::npos) << e;
    EXPECT_NE(
        e.find(
            "tensor backbone.decoder.2.0.weight has shape [128, 255, 1], expected [128, 256, 1]"),
        std::string::npos)
        << e;
}

// The two formats of one state dict read to the same tensors (torch.save wrote both).
TEST_F(AuthorsCheckpoint, LegacyAndZipReadToTheSameTensors) {
    const TorchSaveContents a = ReadTorchSaveFile(File("ogmm_small_legacy.pth").string());
    const TorchSaveContents b = ReadTorchSaveFile(File("ogmm_small_zip.pth").string());
    EXPECT_EQ(a.format, "legacy");
    EXPECT_EQ(b.format, "zip");
    ASSERT_EQ(a.tensors.size(), b.tensors.size());
    for (size_t j = 0; j < a.tensors.size(); ++j) {
        EXPECT_EQ(a.tensors[j].first, b.tensors[j].first);
        EXPECT_TRUE(torch::equal(a.tensors[j].second, b.tensors[j].second)) << a.tensors[j].first;
    }
}

}  // namespace
}  // namespace regbench::networks

namespace regbench::networks {
namespace {

// The fuzz seeds (fuzz/corpus/torch_save, written by python3-torch as noted in
// docs/learned-methods.md): a state dict wrapped under "state_dict" holding a transposed
// (non-contiguous) view, and a legacy file holding a view at storage offset 1. Expected values
// are what torch gave when it wrote them: arange(4).view(2, 2).t() and arange(6)[1:4].
TEST(TorchSaveReader, ViewsOffsetsAndWrappersReadAsTorchWroteThem) {
    const std::string dir = std::string(std::getenv("REGBENCH_SOURCE_DIR") != nullptr
                                            ? std::getenv("REGBENCH_SOURCE_DIR")
                                            : ".") +
                            "/fuzz/corpus/torch_save/";
    const TorchSaveContents w = ReadTorchSaveFile(dir + "wrapped_strided_zip.pth");
    EXPECT_EQ(w.wrapper, "state_dict");
    ASSERT_EQ(w.tensors.size(), 1u);
    EXPECT_TRUE(torch::equal(w.tensors[0].second, torch::tensor({{0.0f, 2.0f}, {1.0f, 3.0f}})));
    const TorchSaveContents o = ReadTorchSaveFile(dir + "offset_legacy.pth");
    EXPECT_EQ(o.format, "legacy");
    ASSERT_EQ(o.tensors.size(), 1u);
    EXPECT_TRUE(torch::equal(o.tensors[0].second, torch::tensor({1, 2, 3}, torch::kLong)));
    const TorchSaveContents b = ReadTorchSaveFile(dir + "bn_legacy.pth");
    ASSERT_EQ(b.tensors.size(), 6u);  // conv weight, BN weight, bias, 3 buffers
    EXPECT_EQ(b.tensors[5].first, "1.num_batches_tracked");
    const std::string e = ErrorOf([&] { ReadTorchSaveFile(dir + "plain.pickle"); });
    EXPECT_NE(e.find("plain.pickle"), std::string::npos) << e;
}

// ---- RIENet (issue 42) --------------------------------------------------------------------

/// The fixtures above plus networks/families/rienet/rienet_standin.py's `checkpoint`: rienet_authors.pth in
/// the layout of the authors' published files ({"model", "optimizer", "epoch", "best_result":
/// np.float64}) with formula weights, and rienet_reference.json, the stand-in's float64
/// forward with those weights on its two cases.
class RienetAuthorsCheckpoint : public AuthorsCheckpoint {
protected:
    static void SetUpTestSuite() {
        AuthorsCheckpoint::SetUpTestSuite();
        if (!missing_.empty() || dir_ == nullptr) return;
        const auto [rc, out] = regbench::testing::RunShell(
            kPython + " " + SourceDir() + "/networks/families/rienet/rienet_standin.py checkpoint " +
            dir_->string() + " 2>&1");
        ASSERT_EQ(rc, 0) << out;
        std::ifstream in(*dir_ / "rienet_reference.json");
        rienet_ref_ = new nlohmann::json(nlohmann::json::parse(in));
    }
    static void TearDownTestSuite() {
        AuthorsCheckpoint::TearDownTestSuite();
        delete rienet_ref_;
        rienet_ref_ = nullptr;
    }
    static ImportOptions FromRienet() {
        ImportOptions o;
        o.from = "rienet";
        return o;
    }
    static inline nlohmann::json* rienet_ref_ = nullptr;
};

// The numpy scalar beside the state dict is read, not refused; the weights import into the
// authors' ModelNet40 config, and the imported network, run in float64 as the stand-in, gives
// its rotation and translation within 1e-4 on both cases (N == M and N != M).
TEST_F(RienetAuthorsCheckpoint, ImportedForwardMatchesTheStandIn) {
    const fs::path pth = File("rienet_authors.pth");
    EXPECT_EQ(ReadTorchSaveFile(pth.string()).wrapper, "model");
    const fs::path ck = File("ck_rienet");
    const nlohmann::json j = ImportAuthorsCheckpoint(pth.string(), ck.string(), FromRienet());
    EXPECT_EQ(j.at("config").at("name"), "rienet");
    EXPECT_EQ(j.at("imported_from").at("wrapper_key"), "model");
    EXPECT_EQ(j.at("mapping").size(), rienet_ref_->at("tensors").get<size_t>());
    const auto net = LoadNetFromCheckpoint(ck.string());
    net->to(torch::kDouble);
    net->eval();
    torch::NoGradGuard no_grad;
    for (const auto& [name, c] : rienet_ref_->at("cases").items()) {
        SCOPED_TRACE(name);
        PairBatch batch;
        batch.source = TensorFromJson(c.at("source"));
        batch.target = TensorFromJson(c.at("target"));
        const torch::Tensor T = net->Forward(batch).T;
        const torch::Tensor want = TensorFromJson(c.at("T"));
        using torch::indexing::Slice;
        EXPECT_LT(MaxAbs(T.index({Slice(), Slice(0, 3), Slice(0, 3)}),
                         want.index({Slice(), Slice(0, 3), Slice(0, 3)})),
                  1e-4);
        EXPECT_LT(MaxAbs(T.index({Slice(), Slice(0, 3), 3}), want.index({Slice(), Slice(0, 3), 3})),
                  1e-4);
    }
}

// The same file under --preset 7scenes (the authors' config/train7.yaml) records their 7Scenes
// settings and runs as the stand-in does with them (float64, within 1e-4 as above); under the
// ModelNet40 defaults the same weights give another transform, so the preset is what matches.
TEST_F(RienetAuthorsCheckpoint, SevenScenesPresetRecordsItsSettingsAndMatchesTheStandIn) {
    ImportOptions o = FromRienet();
    o.preset = "7scenes";
    const fs::path ck = File("ck_rienet_7scenes");
    const nlohmann::json j =
        ImportAuthorsCheckpoint(File("rienet_authors.pth").string(), ck.string(), o);
    const nlohmann::json& c = j.at("config");
    EXPECT_EQ(c.at("k"), 8);
    EXPECT_EQ(c.at("k_nc"), 8);
    EXPECT_EQ(c.at("nn_margin"), 0.5);
    EXPECT_EQ(c.at("keypoints"), 768);
    EXPECT_EQ(c.at("name"), "rienet-authors");  // not the zoo's ModelNet40 `rienet`
    EXPECT_EQ(j.at("imported_from").at("preset"), "7scenes");
    EXPECT_EQ(j.at("imported_from").at("assumed_settings"), nlohmann::json::array());
    const auto net = LoadNetFromCheckpoint(ck.string());
    ImportAuthorsCheckpoint(File("rienet_authors.pth").string(), File("ck_rienet_mn").string(),
                            FromRienet());
    const auto defaults = LoadNetFromCheckpoint(File("ck_rienet_mn").string());
    torch::NoGradGuard no_grad;
    for (auto* n : {net.get(), defaults.get()}) {
        n->to(torch::kDouble);
        n->eval();
    }
    for (const auto& [name, cs] : rienet_ref_->at("cases").items()) {
        SCOPED_TRACE(name);
        PairBatch batch;
        batch.source = TensorFromJson(cs.at("source"));
        batch.target = TensorFromJson(cs.at("target"));
        const torch::Tensor want =
            TensorFromJson(rienet_ref_->at("cases_7scenes").at(name).at("T"));
        EXPECT_LT(MaxAbs(net->Forward(batch).T, want), 1e-4);
        EXPECT_GT(MaxAbs(defaults->Forward(batch).T, want), 1e-3);
    }
}

// Presets and settings are checked before the file is read: an unknown preset, an unknown key
// and a value of another type than the default's are refused naming them.
TEST_F(RienetAuthorsCheckpoint, UnknownPresetsKeysAndTypesAreRefusedByName) {
    const auto error = [&](ImportOptions o) {
        return ErrorOf([&] {
            ImportAuthorsCheckpoint(File("rienet_authors.pth").string(),
                                    File("refused_settings").string(), o);
        });
    };
    ImportOptions o = FromRienet();
    o.preset = "scannet";
    std::string e = error(o);
    EXPECT_NE(e.find("unknown preset 'scannet'"), std::string::npos) << e;
    EXPECT_NE(e.find("7scenes"), std::string::npos) << e;  // lists the known ones
    o.preset = "";
    o.settings = {{"clusters", 64}};
    e = error(o);
    EXPECT_NE(e.find("unknown setting 'clusters'"), std::string::npos) << e;
    o.settings = {{"k", 2.5}};
    e = error(o);
    EXPECT_NE(e.find("setting k = 2.5"), std::string::npos) << e;
    o.settings = {{"k", 8}};
    o.preset = "icl_nuim";  // --setting wins over the preset, the rest is the preset's
    const ResolvedImportSettings r = ResolveImportSettings(o);
    EXPECT_EQ(r.values.at("k"), 8);
    EXPECT_EQ(r.values.at("k_nc"), 10);
    EXPECT_TRUE(r.assumed.empty());
    EXPECT_FALSE(fs::exists(File("refused_settings")));
}

// A DeepGMR checkpoint and truncated copies of the RIENet file are refused, naming the file and
// the problem, and leave no checkpoint folder behind.
TEST_F(RienetAuthorsCheckpoint, DeepGmrAndTruncatedFilesAreRefusedByName) {
    const auto refused = [&](const fs::path& f) {
        const std::string e = ErrorOf(
            [&] { ImportAuthorsCheckpoint(f.string(), File("refused").string(), FromRienet()); });
        EXPECT_FALSE(fs::exists(File("refused"))) << f;
        EXPECT_NE(e.find(f.string()), std::string::npos) << e;
        return e;
    };
    const std::string deepgmr = refused(File("deepgmr_xyz_zip.pth"));
    EXPECT_NE(deepgmr.find("has no tensor emb_nn.model.conv5.weight: not a RIENet state dict"),
              std::string::npos)
        << deepgmr;
    const std::string bytes = testing::ReadBytes(File("rienet_authors.pth"));
    for (const size_t cut : {size_t{1}, size_t{300}, bytes.size() / 2, bytes.size() - 9}) {
        const fs::path t = File("cut_rienet.pth");
        testing::WriteBytes(t, bytes.substr(0, cut));
        refused(t);
    }
}

}  // namespace
}  // namespace regbench::networks
