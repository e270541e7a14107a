// The learned-method registry (networks/family.hpp): lookups, refusals, and each family's
// declaration checked against itself (documented config keys, buildable models, costs).
#include "networks/family.hpp"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <filesystem>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "networks/checkpoint/authors_checkpoint.hpp"
#include "networks/checkpoint/torch_save_reader.hpp"
#include "networks/cost.hpp"
#include "networks/net.hpp"
#include "networks/zoo.hpp"
#include "tests/testing/expect_throw.hpp"
#include "tests/testing/files.hpp"

namespace regbench::networks {
namespace {

TEST(Family, LookupsNameWhatIsKnown) {
    // Every registered family, model and authors' format is found by its name; the lists are
    // the registry's own, so a family added by its folder and one line is covered unchanged.
    std::string arches;
    std::vector<std::string> with_authors;
    for (const auto& f : Families()) {
        EXPECT_EQ(&FindFamily(f.arch), &f);
        for (const auto& m : f.models) EXPECT_EQ(&FamilyOfModel(m), &f) << m;
        EXPECT_EQ(&FamilyOfConfig(nlohmann::json{{"arch", f.arch}}), &f);
        arches += (arches.empty() ? "" : ", ") + f.arch;
        if (f.authors) with_authors.push_back(f.arch);
    }
    testing::ExpectThrowsWith<std::invalid_argument>([] { FindFamily("dcp"); }, "'dcp'", arches);
    testing::ExpectThrowsWith<std::invalid_argument>([] { FamilyOfModel("ogmm-huge"); },
                                                     "unknown model 'ogmm-huge'", "ogmm-tiny");
    // Checkpoints written before configs recorded "arch" hold OGMM networks.
    EXPECT_EQ(FamilyOfConfig(nlohmann::json{{"emb_dims", 64}}).arch, "ogmm");
    EXPECT_THROW(FamilyOfConfig(nlohmann::json{{"arch", 3}}), std::invalid_argument);
    EXPECT_THROW(FamilyOfConfig(nlohmann::json::array()), std::invalid_argument);
    EXPECT_EQ(AuthorsFormats(), with_authors);
}

TEST(Family, ATakenNameOrAnIncompleteFamilyIsRefused) {
    NetworkFamily copy = FindFamily("deepgmr");
    testing::ExpectThrowsWith<std::invalid_argument>([&] { RegisterFamily(copy); },
                                                     "'deepgmr' is registered");
    copy.arch = "deepgmr-2";
    testing::ExpectThrowsWith<std::invalid_argument>([&] { RegisterFamily(copy); },
                                                     "model 'deepgmr'", "of 'deepgmr'");
    copy.models = {"deepgmr-2"};
    testing::ExpectThrowsWith<std::invalid_argument>([&] { RegisterFamily(copy); },
                                                     "method 'deepgmr'");
    copy.methods.clear();
    copy.build = nullptr;
    const std::size_t before = Families().size();
    testing::ExpectThrowsWith<std::invalid_argument>([&] { RegisterFamily(copy); }, "required");
    EXPECT_EQ(Families().size(), before);  // nothing refused was added
}

// Every family documents exactly its config keys: each key of each model's config (but arch,
// name, train) has a doc, and each doc names a key a model has.
TEST(Family, EveryConfigKeyHasOneDoc) {
    for (const auto& f : Families()) {
        std::set<std::string> keys;
        for (const auto& m : f.models) {
            const nlohmann::json config = f.named_config(m);
            for (const auto& item : config.items()) {
                if (item.key() != "arch" && item.key() != "name" && item.key() != "train") {
                    keys.insert(item.key());
                    EXPECT_EQ(f.config_docs.count(item.key()), 1u)
                        << f.arch << " model " << m << ": key " << item.key() << " has no doc";
                }
            }
        }
        for (const auto& [key, doc] : f.config_docs) {
            EXPECT_FALSE(doc.empty()) << f.arch << ": " << key;
            // DeepGMR writes d_model only when it is not 1024 (no model here changes it).
            EXPECT_TRUE(keys.count(key) != 0 || key == "d_model") << f.arch << ": " << key;
        }
    }
}

TEST(Family, EveryModelChecksBuildsAndHasACost) {
    for (const auto& f : Families()) {
        EXPECT_FALSE(f.methods.empty()) << f.arch;
        for (const auto& m : f.models) {
            const nlohmann::json c = NamedConfig(m);
            EXPECT_EQ(c.at("arch"), f.arch) << m;
            EXPECT_EQ(c.at("name"), m);
            EXPECT_TRUE(c.at("train").is_object()) << m;
            nlohmann::json net = c;
            net.erase("train");
            EXPECT_NO_THROW(f.check_config(net)) << m;
            EXPECT_GT(ComputeForwardCost(c, 717, 717).total, 0) << m;
        }
    }
    // Built once (the smallest), its Config() is what its checkpoints store.
    const auto net = MakeNet("ogmm-tiny");
    EXPECT_EQ(net->Config().at("emb_dims"), 64);
}

TEST(Family, AbsurdSizesAreRefusedBeforeAnythingIsBuilt) {
    // Issue 44: checkpoint configs with clusters 1e9 used to fail every row of a run (exit 0);
    // the families' checks refuse them by name (limits: networks/families/ogmm/net.cpp,
    // networks/families/deepgmr/net.cpp).
    for (const auto& [model, key, value] :
         std::vector<std::tuple<std::string, std::string, double>>{
             {"ogmm-tiny", "clusters", 1e9},
             {"ogmm-tiny", "emb_dims", 1e6},
             {"ogmm-tiny", "k", 5000},
             {"ogmm-tiny", "gmm_iterations", 1e9},
             {"deepgmr-small", "clusters", 1e9},
             {"deepgmr-orig", "d_model", 1e6},
             {"deepgmr-orig", "d_model", 1e12},
             {"deepgmr-orig", "rri_k", 1e5},
             {"rienet", "k", 1},
             {"rienet", "k", 5000},
             {"rienet", "emb_dims", 1e6},
             {"rienet", "keypoints", 1e9}}) {
        nlohmann::json c = NamedConfig(model);
        c.erase("train");
        c[key] = value;
        testing::ExpectThrowsWith<std::invalid_argument>([&] { FamilyOfConfig(c).check_config(c); },
                                                         key);
    }
}

// Every family with an authors' format refuses, naming the file and writing nothing, a file cut
// short and the state dict of another network (a tensor no family has): the generic half of
// each family's import test, which keeps what is particular to it.
TEST(Family, AuthorsImportRefusesACutFileAndAnotherNetworkByName) {
    const std::filesystem::path dir = testing::FreshTempDir("family_authors_refusals");
    const std::string other = WriteTorchSaveZip({{"unrelated.weight", torch::zeros({4, 3})}});
    testing::WriteBytes(dir / "other.pth", other);
    testing::WriteBytes(dir / "cut.pth", other.substr(0, other.size() / 2));
    for (const std::string& arch : AuthorsFormats()) {
        ImportOptions options;
        options.from = arch;
        for (const char* name : {"cut.pth", "other.pth"}) {
            const std::string pth = (dir / name).string();
            const std::string e = testing::ErrorOf(
                [&] { ImportAuthorsCheckpoint(pth, (dir / "out").string(), options); });
            EXPECT_NE(e.find(pth), std::string::npos) << arch << ": " << e;
            if (std::string(name) == "other.pth") {
                EXPECT_NE(e.find("has no tensor"), std::string::npos) << arch << ": " << e;
            }
            EXPECT_FALSE(std::filesystem::exists(dir / "out")) << arch;
        }
    }
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace regbench::networks
