// Issue 55, item 4: an RGM checkpoint with NaN, Inf or 3e38 weights imported with exit 0 and
// `run` gave the identity in `ok` rows. Expected: import and load refuse a tensor holding NaN,
// Inf or a value beyond kMaxAbsWeight (1e30), naming the file and the tensor, and a network
// whose output transform is not finite fails the call, for all six families. The weights are
// the shipped checkpoints (data/models/<family>) with one value changed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "core/point_cloud.hpp"
#include "core/rng.hpp"
#include "networks/checkpoint/authors_checkpoint.hpp"
#include "networks/checkpoint/authors_format.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/inference.hpp"
#include "networks/net.hpp"
#include "networks/checkpoint/torch_save_reader.hpp"
#include "networks/zoo.hpp"
#include "tests/testing/files.hpp"

namespace regbench::networks {
namespace {
namespace fs = std::filesystem;

using testing::ErrorOf;

/// The poisons and the words the refusal must use for each.
const std::vector<std::pair<double, std::string>>& Poisons() {
    static const std::vector<std::pair<double, std::string>> p = {
        {std::numeric_limits<double>::quiet_NaN(), "holds NaN"},
        {std::numeric_limits<double>::infinity(), "holds Inf"},
        {-std::numeric_limits<double>::infinity(), "holds Inf"},
        {3e38, "holds |w| = 3e+38, beyond the bound 1e+30"},
        {-2e30, "holds |w| = 2e+30, beyond the bound 1e+30"}};
    return p;
}

/// Sets element 0 of `t` (a copy; the caller's tensor is untouched) to `value`.
torch::Tensor WithValue(const torch::Tensor& t, double value) {
    torch::Tensor c = t.detach().clone();
    c.view({-1})[0] = value;
    return c;
}

TEST(PoisonedWeights, ImportRefusesThemNamingTheFileAndTheTensor) {
    torch::set_num_threads(1);
    const fs::path dir = testing::FreshTempDir("poisoned_import");
    for (const std::string family : {"rgm", "rienet", "regtr"}) {
        const StateDict clean =
            ExportAuthorsStateDict(testing::ShippedModel(family).string(), family);
        ImportOptions o;
        o.from = family;
        // The last floating tensor: deep in the network, after every shape check.
        std::size_t at = clean.size();
        for (std::size_t j = 0; j < clean.size(); ++j)
            if (clean[j].second.is_floating_point() && clean[j].second.numel() > 0) at = j;
        ASSERT_LT(at, clean.size());
        const std::string name = clean[at].first;
        for (const auto& [value, why] : Poisons()) {
            SCOPED_TRACE(family + " " + name + " = " + std::to_string(value));
            StateDict sd = clean;
            sd[at].second = WithValue(sd[at].second.to(torch::kDouble), value);
            const fs::path pth = dir / (family + ".pth");
            testing::WriteBytes(pth, WriteTorchSaveZip(sd));
            const fs::path out = dir / "out";
            const std::string e =
                ErrorOf([&] { ImportAuthorsCheckpoint(pth.string(), out.string(), o); });
            EXPECT_NE(e.find(pth.string()), std::string::npos) << e;
            EXPECT_NE(e.find("tensor " + name + " " + why), std::string::npos) << e;
            EXPECT_FALSE(fs::exists(out));
        }
        // Within the bound: imported.
        StateDict sd = clean;
        sd[at].second = WithValue(sd[at].second.to(torch::kDouble), 1e29);
        const fs::path pth = dir / (family + "_large.pth");
        testing::WriteBytes(pth, WriteTorchSaveZip(sd));
        const fs::path ck = dir / family;
        EXPECT_EQ(ErrorOf([&] { ImportAuthorsCheckpoint(pth.string(), ck.string(), o); }), "");
    }
    fs::remove_all(dir);
}

TEST(PoisonedWeights, LoadRefusesThemNamingTheFileAndTheTensor) {
    torch::set_num_threads(1);
    const fs::path dir = testing::FreshTempDir("poisoned_load");
    auto net = MakeNet("deepgmr-orig-xyz");
    const auto params = net->named_parameters();
    const std::string name = params.keys().back();
    const torch::Tensor original = params[name].detach().clone();
    for (const auto& [value, why] : Poisons()) {
        SCOPED_TRACE(value);
        {
            torch::NoGradGuard no_grad;
            params[name].copy_(WithValue(original, value));
        }
        const fs::path ck = dir / "ck";
        SaveCheckpoint(ck.string(), *net, {});
        const std::string e = ErrorOf([&] { LoadNetFromCheckpoint(ck.string()); });
        EXPECT_NE(e.find((ck / "weights.pt").string()), std::string::npos) << e;
        EXPECT_NE(e.find("tensor " + name + " " + why), std::string::npos) << e;
    }
    {
        torch::NoGradGuard no_grad;
        params[name].copy_(WithValue(original, 1e29));
    }
    SaveCheckpoint((dir / "ck").string(), *net, {});
    EXPECT_EQ(ErrorOf([&] { LoadNetFromCheckpoint((dir / "ck").string()); }), "");
    fs::remove_all(dir);
}

/// A pair of 256 points: a random cloud and the same cloud rotated about z by 0.3 rad.
std::pair<PointCloud, PointCloud> SmallPair() {
    std::mt19937_64 rng(7);
    PointCloud source(256, 3);
    for (Eigen::Index i = 0; i < source.rows(); ++i)
        for (int c = 0; c < 3; ++c) source(i, c) = UniformReal(rng, -0.5, 0.5);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    PointCloud target = (source * R.transpose()).eval();
    return {source, target};
}

// Every family's shipped network with NaN in every weight: the call fails with a message saying
// so (RGM's came out as a finite transform: its assignment hid the NaN), instead of a rigid
// transform in an `ok` row; the clean network first runs without an error on the same pair.
TEST(PoisonedWeights, ANonFiniteOutputIsAFailedCallForEveryFamily) {
    torch::set_num_threads(1);
    const auto [source, target] = SmallPair();
    for (const std::string family : {"deepgmr", "ogmm", "omnet", "rienet", "rgm", "regtr"}) {
        SCOPED_TRACE(family);
        const auto net = LoadNetFromCheckpoint(testing::ShippedModel(family).string());
        EXPECT_EQ(ErrorOf([&] { EstimatePair(*net, source, target, 1, 1); }), "");
        {
            torch::NoGradGuard no_grad;
            for (auto& p : net->parameters()) p.fill_(std::numeric_limits<float>::quiet_NaN());
        }
        // Either the NaN reaches an output ("not finite") or an SVD on the way refuses it
        // ("non-finite values"): a failed call either way, saying why, never a transform.
        const std::string e = ErrorOf([&] { EstimatePair(*net, source, target, 1, 1); });
        EXPECT_NE(e.find("finite"), std::string::npos) << e;
        EXPECT_EQ(e.find("Exception raised from"), std::string::npos) << e;  // no stack dump
    }
}

}  // namespace
}  // namespace regbench::networks
