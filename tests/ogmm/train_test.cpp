#include "ogmm/train.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "ogmm/zoo.hpp"
#include "synthetic_pairs.hpp"

namespace regbench::ogmm {
namespace {
namespace fs = std::filesystem;

/// A fresh (emptied) per-process directory; call once per run directory, since it clears it.
fs::path TempDir(const std::string& name) {
    const fs::path d =
        fs::temp_directory_path() / ("regbench_train_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(d);
    return d;
}

nlohmann::json SmallRecipe(const std::string& model) {
    nlohmann::json c = NamedConfig(model);
    c["train"]["batch"] = 2;
    c["train"]["pairs_per_epoch"] = 20;
    c["train"]["epochs"] = 2;
    return c;
}

TrainOptions Options(const fs::path& dir, std::ostream& log) {
    TrainOptions o;
    o.out_dir = dir.string();
    o.seed = 5;
    o.threads = 1;
    o.log = &log;
    return o;
}

TEST(Train, SameSeedGivesTheSameLossCurve) {
    torch::set_num_threads(1);
    const TrainData data = testing::SyntheticData(3, 160, 2);
    std::ostringstream log;
    const nlohmann::json config = SmallRecipe("deepgmr-orig-xyz");  // 10 steps per epoch
    const fs::path dir_a = TempDir("a");
    const fs::path dir_b = TempDir("b");
    const TrainSummary a = Train(config, data, Options(dir_a, log));
    const TrainSummary b = Train(config, data, Options(dir_b, log));
    ASSERT_EQ(a.step_losses.size(), 20u);
    EXPECT_EQ(a.step_losses, b.step_losses);
    EXPECT_NE(a.step_losses.front(), a.step_losses.back());
    // Two validations, recorded in both formats.
    std::ifstream csv(dir_a / "metrics.csv");
    std::string line;
    int lines = 0;
    while (std::getline(csv, line)) ++lines;
    EXPECT_EQ(lines, 3);
    EXPECT_TRUE(fs::exists(dir_a / "best" / "checkpoint.json"));
    fs::remove_all(dir_a);
    fs::remove_all(dir_b);
}

TEST(Train, ResumeContinuesTheSameCurve) {
    torch::set_num_threads(1);
    const TrainData data = testing::SyntheticData(4, 160, 2);
    std::ostringstream log;
    const nlohmann::json config = SmallRecipe("deepgmr-orig-xyz");
    const fs::path dir_full = TempDir("full");
    const fs::path dir_split = TempDir("split");
    const TrainSummary full = Train(config, data, Options(dir_full, log));
    TrainOptions first = Options(dir_split, log);
    first.max_steps = 10;
    const TrainSummary part1 = Train(config, data, first);
    TrainOptions second = Options(dir_split, log);
    second.resume = true;
    const TrainSummary part2 = Train(config, data, second);
    std::vector<double> joined = part1.step_losses;
    joined.insert(joined.end(), part2.step_losses.begin(), part2.step_losses.end());
    EXPECT_EQ(joined, full.step_losses);
    // A second run into the same directory without --resume is refused.
    EXPECT_THROW(Train(config, data, Options(dir_full, log)), std::runtime_error);
    fs::remove_all(dir_full);
    fs::remove_all(dir_split);
}

}  // namespace
}  // namespace regbench::ogmm
