// The worked example of docs/adding-a-learned-method.md, compiled and tested so the document
// cannot rot: a network family `centroid-net` (not in the tree) declared once, registered,
// trained for two steps, imported from an "authors'" state dict, and run as a regbench method
// on a 40,000-point pair file. The block between the EXAMPLE markers is the document's
// networks/families/centroid_net/family.cpp verbatim; keep them in step. In the tree the family
// has its line in networks/families/families.def; here RegisterFamily adds the same object
// before the registry is first used.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "core/rng.hpp"
#include "core/transform.hpp"
#include "networks/checkpoint/authors_checkpoint.hpp"
#include "networks/checkpoint/authors_format.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/cost.hpp"
#include "networks/family.hpp"
#include "networks/family_config.hpp"
#include "networks/net.hpp"
#include "networks/training/train.hpp"
#include "networks/zoo.hpp"
#include "runners/registry.hpp"
#include "runners/result_row.hpp"
#include "runners/runner.hpp"
#include "tests/baselines/method_contract.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/synthetic_pair_file.hpp"
#include "tests/testing/temp_dir_test.hpp"

namespace regbench::networks {

// EXAMPLE BEGIN
using torch::indexing::Slice;

/// Its config, declared once (networks/family_config.hpp): from Fields and Validate come the
/// JSON, the checks, `train --list-models`' docs and ranges.
struct CentroidNetConfig {
    std::string name = "centroid-net";  ///< zoo model it came from
    bool bias = true;                   ///< the learned 3x3 map has a bias

    template <class F>
    void Fields(F&& f) {
        f("name", name, "zoo model it came from");
        f("bias", bias, "the learned 3x3 map has a bias");
    }
    void Validate(ParamCheck& /*c*/) const {}  // no numbers, so no ranges
};

/// The config as JSON (what Config() returns and a checkpoint stores).
nlohmann::json ToJson(const CentroidNetConfig& c) { return NetConfigJson(c, "centroid-net"); }

/// A toy network: the offset between the clouds' centroids through a learned 3x3 map (and
/// bias); the rotation is the identity.
class CentroidNet : public RegistrationNet {
public:
    explicit CentroidNet(const CentroidNetConfig& config) : config_(config) {
        offset_ = register_module(
            "offset", torch::nn::Linear(torch::nn::LinearOptions(3, 3).bias(config.bias)));
    }
    NetOutput Forward(const PairBatch& batch) override {
        const torch::Tensor d = batch.target.mean(1) - batch.source.mean(1);  // [B, 3]
        const torch::Tensor t = offset_->forward(d);
        const int64_t b = d.size(0);
        const torch::Tensor R = torch::eye(3, d.options()).expand({b, 3, 3});
        const torch::Tensor last = torch::eye(4, d.options()).index({Slice(3, 4)});  // 0 0 0 1
        NetOutput out;
        out.T = torch::cat({torch::cat({R, t.unsqueeze(2)}, 2), last.expand({b, 1, 4})}, 1);
        return out;
    }
    LossTerms Loss(const PairBatch& batch, const NetOutput& output) override {
        const torch::Tensor t = output.T.index({Slice(), Slice(0, 3), 3});
        const torch::Tensor t_gt = batch.T_gt.index({Slice(), Slice(0, 3), 3});
        LossTerms terms;
        terms["translation"] = (t - t_gt).pow(2).mean();
        terms["total"] = terms["translation"];
        return terms;
    }
    nlohmann::json Config() const override { return ToJson(config_); }

private:
    CentroidNetConfig config_;
    torch::nn::Linear offset_{nullptr};
};

/// The zoo: one model, the config's defaults (no change), and its training recipe.
const std::vector<ZooModel<CentroidNetConfig>>& CentroidNetModels() {
    static const std::vector<ZooModel<CentroidNetConfig>> kModels = {
        {"centroid-net",
         [](CentroidNetConfig&) {},
         {{"lr", 0.05},
          {"batch", 4},
          {"epochs", 2},
          {"pairs_per_epoch", 16},
          {"schedule", "constant"}}}};
    return kModels;
}

/// Multiply-accumulates by part: the 3x3 map; the two means are additions.
std::map<std::string, int64_t> CentroidNetMacs(const CentroidNetConfig& /*c*/, int64_t /*n*/,
                                               int64_t /*m*/) {
    return {{"offset", 9}};
}

/// The "authors'" layout: one nn.Linear(3, 3) named fc.
nlohmann::json InferCentroidNetConfig(const StateDict& sd, const std::string& file,
                                      const nlohmann::json& /*settings*/) {
    RequireAuthorsTensor(sd, "fc.weight", 2, file, "a CentroidNet");
    nlohmann::json c = ZooModelConfig(CentroidNetModels(), "centroid-net", ToJson);
    c["bias"] = false;
    for (const auto& [key, tensor] : sd) c["bias"] = c["bias"] || key == "fc.bias";
    return c;
}

NetworkFamily CentroidNetFamily() {
    // Models, shipped model, config docs and checks, build and cost, from the three above.
    NetworkFamily f = NetFamily<CentroidNetConfig, CentroidNet>(
        "centroid-net", "worked example: a learned map of the centroid offset",
        CentroidNetModels(), ToJson, CentroidNetMacs);
    f.cost_class = CostClass::kNearLinear;  // two means: O(N + M)
    f.methods = {{"centroid-net", false, "worked example: centroid offset, learned 3x3 map"}};
    AuthorsFormat authors{"CentroidNet (fc = nn.Linear(3, 3))", InferCentroidNetConfig};
    authors.authors_name = [](const std::string& name) {  // offset.weight -> fc.weight
        return "fc." + name.substr(name.find('.') + 1);
    };
    f.authors = std::make_shared<AuthorsFormat>(std::move(authors));
    return f;
}
// EXAMPLE END

namespace {
namespace fs = std::filesystem;

const bool kRegistered = [] {
    RegisterFamily(CentroidNetFamily());
    return true;
}();

/// A random cloud moved by a random translation: the training stream, pair `index`.
TrainSample TranslatedCloud(std::uint64_t index) {
    std::mt19937_64 rng = MakePairRng(1000, index);
    const auto u = [&] { return UniformReal(rng, -1.0, 1.0); };
    TrainSample s;
    s.source.resize(64, 3);
    for (Eigen::Index i = 0; i < s.source.size(); ++i) s.source.data()[i] = u();
    const Eigen::Vector3d t(u(), u(), u());
    s.T_gt = MakeTransform(Eigen::Matrix3d::Identity(), t);
    s.target = s.source.rowwise() + t.transpose();
    return s;
}

/// The "authors'" file of the example: fc = the identity map without bias, so the method's
/// translation is exactly the centroid offset.
std::string WriteIdentityAuthorsFile(const fs::path& path) {
    const StateDict sd = {{"fc.weight", torch::eye(3)}};
    std::ofstream(path, std::ios::binary) << WriteTorchSaveZip(sd);
    return path.string();
}

/// What the tree would ship for the example: $REGBENCH_MODELS/centroid-net, imported from the
/// identity file, beside links to the tree's shipped models, so that the method runs with its
/// defaults as every method of the contract tests does.
class ShippedExampleModel : public ::testing::Environment {
public:
    void SetUp() override {
        const fs::path models = testing::FreshTempDir("learned_example_models");
        const fs::path tree = fs::absolute(testing::ShippedModel("ogmm").parent_path());
        for (const auto& entry : fs::directory_iterator(tree)) {
            fs::create_directory_symlink(entry.path(), models / entry.path().filename());
        }
        ImportOptions import;
        import.from = "centroid-net";
        ImportAuthorsCheckpoint(WriteIdentityAuthorsFile(models / "centroid.pth"),
                                (models / "centroid-net").string(), import);
        setenv("REGBENCH_MODELS", models.c_str(), 1);
    }
};
::testing::Environment* const kShipped =
    ::testing::AddGlobalTestEnvironment(new ShippedExampleModel);

// The contract every registered method keeps (tests/baselines/method_contract.hpp), on the
// example and nothing else: no tolerance row, no other file.
using testing::MethodContract;
INSTANTIATE_TEST_SUITE_P(Example, MethodContract, ::testing::Values("centroid-net"),
                         testing::MethodContractName);

class LearnedExample : public testing::TempDirTest {};

TEST_F(LearnedExample, IsAModelAMethodAndAnImportFormat) {
    ASSERT_TRUE(kRegistered);
    EXPECT_EQ(FamilyOfModel("centroid-net").arch, "centroid-net");
    EXPECT_EQ(FindMethod("centroid-net").name, "centroid-net");
    EXPECT_EQ(MethodCost("centroid-net"), CostClass::kNearLinear);
    bool listed = false;
    for (const auto& f : AuthorsFormats()) listed = listed || f == "centroid-net";
    EXPECT_TRUE(listed);
    EXPECT_EQ(ComputeForwardCost(NamedConfig("centroid-net"), 40000, 40000).total, 9);
    EXPECT_THROW(MakeNet("centroid-net", {{"bias", 1}}), std::invalid_argument);
    EXPECT_THROW(RegisterFamily(CentroidNetFamily()), std::invalid_argument);  // taken
}

TEST_F(LearnedExample, TrainsImportsAndRunsOnA40000PointPairFile) {
    // Two training steps write the run folder's checkpoints.
    TrainData data;
    data.train_pair = TranslatedCloud;
    data.validation = {TranslatedCloud(90001), TranslatedCloud(90002)};
    TrainOptions options;
    options.out_dir = Path("run");
    options.max_steps = 2;
    std::ostringstream log;
    options.log = &log;
    const TrainSummary summary = Train(NamedConfig("centroid-net"), data, options);
    EXPECT_EQ(summary.steps, 2);
    ASSERT_TRUE(fs::exists(fs::path(Path("run")) / "last" / kCheckpointJson)) << log.str();

    ImportOptions import;
    import.from = "centroid-net";
    const nlohmann::json imported = ImportAuthorsCheckpoint(
        WriteIdentityAuthorsFile(Path("centroid.pth")), Path("imported"), import);
    EXPECT_EQ(imported.at("config").at("bias"), false);

    // 40,000 points: the scale guard asks the method (near-linear), so the run goes ahead, while
    // a quadratic learned method on the same file is refused before it starts.
    const std::string pairs = Path("pairs.h5");
    const Eigen::Vector3d t(0.1, -0.2, 0.3);
    testing::WriteSyntheticPairFile(
        pairs, 1, 40000, 7, 1, [&](int) { return MakeTransform(Eigen::Matrix3d::Identity(), t); });
    RunOptions run;
    run.pairs_path = pairs;
    run.out_path = Path("rows.jsonl");
    run.progress = false;
    run.methods = {{"centroid-net", {{"checkpoint", Path("imported")}}}};
    RunBenchmark(run);
    const auto rows = ReadResultRows(run.out_path);
    ASSERT_EQ(rows.size(), 1u);
    ASSERT_EQ(rows[0].result.status, AlignStatus::kOk) << rows[0].result.message;
    // Expected: the centroid offset of the stored clouds, computed here with Eigen in double
    // (the network computes it in float32).
    const PairSet set = ReadPairFile(pairs);
    const Eigen::Vector3d offset =
        (set.pairs[0].target.colwise().mean() - set.pairs[0].source.colwise().mean()).transpose();
    const Eigen::Vector3d got = rows[0].result.T_target_source.block<3, 1>(0, 3);
    EXPECT_LT((got - offset).norm(), 1e-5) << got.transpose() << " vs " << offset.transpose();

    RunOptions trained = run;
    trained.out_path = Path("trained.jsonl");
    trained.methods = {{"centroid-net", {{"checkpoint", Path("run") + "/best"}}}};
    RunBenchmark(trained);
    EXPECT_EQ(ReadResultRows(trained.out_path).at(0).result.status, AlignStatus::kOk);

    RunOptions quadratic = run;
    quadratic.out_path = Path("refused.jsonl");
    quadratic.methods = {{"ogmm-noicp", nlohmann::json::object()}};
    EXPECT_THROW(RunBenchmark(quadratic), std::runtime_error);
    EXPECT_FALSE(fs::exists(quadratic.out_path));
}

}  // namespace
}  // namespace regbench::networks
