#include "networks/training/train.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>

#include "networks/checkpoint/checkpoint.hpp"
#include "networks/layers/edge_stages.hpp"
#include "networks/training/train_batch.hpp"
#include "networks/zoo.hpp"
#include "synthetic_pairs.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/kill_save.hpp"

namespace regbench::networks {
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

/// Options of a test run into `dir`, logging to `log`; stopped after `max_steps` (0 = the
/// recipe's epochs), continuing the run already in `dir` when `resume`.
TrainOptions Options(const fs::path& dir, std::ostream& log, std::int64_t max_steps = 0,
                     bool resume = false) {
    TrainOptions o;
    o.out_dir = dir.string();
    o.seed = 5;
    o.threads = 1;
    o.log = &log;
    o.max_steps = max_steps;
    o.resume = resume;
    return o;
}

constexpr bool kResume = true;  ///< Options' last argument, named at the call

/// Runs of the small deepgmr-orig-xyz recipe (10 steps per epoch, 2 epochs) on 4 synthetic
/// shapes, on one thread: the resume and metrics-file tests.
class SmallTrain : public ::testing::Test {
protected:
    void SetUp() override { torch::set_num_threads(1); }

    const TrainData data = testing::SyntheticData(4, 160, 2);
    const nlohmann::json config = SmallRecipe("deepgmr-orig-xyz");
    std::ostringstream log;
};

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

/// deepgmr-small (the DGCNN variant) shrunk for tests: d 32, J 8, k 8.
nlohmann::json ShrunkDgcnnDeepGmr() {
    nlohmann::json config = SmallRecipe("deepgmr-small");  // batch 2, 10 steps an epoch, 2 epochs
    config["emb_dims"] = 32;
    config["head_hidden"] = 32;
    config["clusters"] = 8;
    config["dgcnn_k"] = 8;
    return config;
}

// Issue 21: the fused DGCNN edge stages (networks/layers/edge_stages.hpp, the default in training) against
// the LibTorch composition they replaced (EdgeStagesReference, the code before them): 20 fixed
// training steps (forward, loss, backward, Adam) of a DGCNN DeepGMR in double precision, where
// rounding cannot move either curve, give the same losses to 1e-9.
TEST(Train, FusedEdgeStagesGiveTheSameLossCurveInDouble) {
    torch::set_num_threads(1);
    const TrainData data = testing::SyntheticData(3, 160, 2);
    std::vector<double> curves[2];
    for (int fused = 0; fused < 2; ++fused) {
        SetFusedEdgeStages(fused == 1);
        torch::manual_seed(11);
        const auto net = MakeNetFromConfig(ShrunkDgcnnDeepGmr());
        net->to(torch::kDouble);
        net->train();
        torch::optim::Adam opt(net->parameters(), torch::optim::AdamOptions(1e-3));
        for (std::uint64_t step = 0; step < 20; ++step) {
            PairBatch batch =
                Collate({data.train_pair(2 * step), data.train_pair(2 * step + 1)}, torch::kCPU);
            batch.source = batch.source.to(torch::kDouble);
            batch.target = batch.target.to(torch::kDouble);
            batch.T_gt = batch.T_gt.to(torch::kDouble);
            const torch::Tensor loss = net->Loss(batch, net->Forward(batch)).at("total");
            opt.zero_grad();
            loss.backward();
            opt.step();
            curves[fused].push_back(loss.item<double>());
        }
    }
    SetFusedEdgeStages(true);
    ASSERT_EQ(curves[1].size(), 20u);
    EXPECT_NE(curves[0].front(), curves[0].back());
    for (size_t i = 0; i < curves[0].size(); ++i) {
        EXPECT_NEAR(curves[1][i], curves[0][i], 1e-9 * std::max(1.0, std::abs(curves[0][i])))
            << "step " << i;
    }
}

// The same comparison through Train() in float, for the DGCNN DeepGMR and OGMM (shrunk). The
// first step's loss (same weights, same batch, so the forward alone) agrees to 1e-5. Later steps
// drift apart because each side rounds its gradients differently and Adam's normalised first
// steps amplify that: LibTorch's float BatchNorm backward is itself off by 0.2-0.3% from the
// double result where the fused one is within 1e-6
// (EdgeStages.FusedFloatErrorIsThatOfTheLibTorchComposition). Measured: DeepGMR's steps differ
// by at most 0.44% (bound 2%); OGMM's loss, with its FPS anchors and Sinkhorn stopping rule, is
// chaotic in float (1.3% with one BLAS thread, 7% at one step with two), so for it the bound is
// on the mean loss of the 20 steps (5%).
TEST(Train, FusedEdgeStagesGiveTheLossCurveOfTheLibTorchCompositionInFloat) {
    torch::set_num_threads(1);
    const TrainData data = testing::SyntheticData(3, 160, 2);
    for (const std::string model : {"deepgmr-small", "ogmm-tiny"}) {
        nlohmann::json config = ShrunkDgcnnDeepGmr();
        if (model == "ogmm-tiny") {
            config = SmallRecipe(model);
            config["emb_dims"] = 32;
            config["k"] = 8;
            config["anchors"] = 8;
            config["clusters"] = 8;
        }
        std::ostringstream log;
        const fs::path dir_ref = TempDir("ref_" + model);
        const fs::path dir_fused = TempDir("fused_" + model);
        SetFusedEdgeStages(false);
        const TrainSummary ref = Train(config, data, Options(dir_ref, log));
        SetFusedEdgeStages(true);
        const TrainSummary fused = Train(config, data, Options(dir_fused, log));
        ASSERT_EQ(ref.step_losses.size(), 20u) << model;
        ASSERT_EQ(fused.step_losses.size(), 20u) << model;
        EXPECT_NEAR(fused.step_losses[0], ref.step_losses[0], 1e-5 * std::abs(ref.step_losses[0]))
            << model;
        double worst = 0.0, mean_ref = 0.0, mean_fused = 0.0;
        for (size_t i = 0; i < ref.step_losses.size(); ++i) {
            const double rel =
                std::abs(fused.step_losses[i] - ref.step_losses[i]) / std::abs(ref.step_losses[i]);
            worst = std::max(worst, rel);
            mean_ref += ref.step_losses[i] / 20.0;
            mean_fused += fused.step_losses[i] / 20.0;
            if (model == "deepgmr-small") {
                EXPECT_LE(rel, 0.02) << model << " step " << i << ": " << fused.step_losses[i]
                                     << " vs " << ref.step_losses[i];
            }
        }
        EXPECT_NEAR(mean_fused, mean_ref, 0.05 * mean_ref) << model;
        std::cout << model << ": largest relative loss difference over 20 steps " << worst
                  << ", mean loss " << mean_ref << " (reference) / " << mean_fused << " (fused)\n";
        fs::remove_all(dir_ref);
        fs::remove_all(dir_fused);
    }
}

TEST_F(SmallTrain, ResumeContinuesTheSameCurve) {
    const fs::path dir_full = TempDir("full");
    const fs::path dir_split = TempDir("split");
    const TrainSummary full = Train(config, data, Options(dir_full, log));
    const TrainSummary part1 = Train(config, data, Options(dir_split, log, 10));
    const TrainSummary part2 = Train(config, data, Options(dir_split, log, 0, kResume));
    std::vector<double> joined = part1.step_losses;
    joined.insert(joined.end(), part2.step_losses.begin(), part2.step_losses.end());
    EXPECT_EQ(joined, full.step_losses);
    // A second run into the same directory without --resume is refused.
    EXPECT_THROW(Train(config, data, Options(dir_full, log)), std::runtime_error);
    fs::remove_all(dir_full);
    fs::remove_all(dir_split);
}

// Issue 27: a checkpoint whose trainer.step is 1e30 was converted to -9.2e18 and the run then
// ignored --max-steps. Expected: --resume refuses it naming checkpoint.json and the key, as
// written (1e30 is not a whole number in [0, 2^53]).
TEST_F(SmallTrain, ResumeRefusesACheckpointWithCountersOutOfRange) {
    const fs::path dir = TempDir("counters");
    Train(config, data, Options(dir, log, 2));
    const fs::path json = dir / "last" / "checkpoint.json";
    nlohmann::json j;
    std::ifstream(json) >> j;
    j["trainer"]["step"] = 1e30;
    std::ofstream(json) << j.dump();
    std::string err;
    try {
        Train(config, data, Options(dir, log, 0, kResume));
    } catch (const std::exception& e) {
        err = e.what();
    }
    EXPECT_NE(err.find(json.string()), std::string::npos) << err;
    EXPECT_NE(err.find("'step' is 1e+30"), std::string::npos) << err;
    fs::remove_all(dir);
}

// `train --resume` without the run's `--no-jitter` carried on a noise-free RIENet run on
// jittered pairs, silently (2026-12-06). Expected: --resume refuses pairs other than the
// checkpoint's (its `data` provenance), naming the directory, the key and both values.
TEST_F(SmallTrain, ResumeRefusesOtherTrainingPairs) {
    const fs::path dir = TempDir("pairs");
    TrainData clean = data;
    clean.provenance = {{"dataset", "cgal"}, {"protocol", {{"noise_sigma", 0.0}, {"pairing", "shared"}}}};
    Train(config, clean, Options(dir, log, 2));
    TrainData jittered = clean;
    jittered.provenance["protocol"]["noise_sigma"] = 0.01;
    std::string err;
    try {
        Train(config, jittered, Options(dir, log, 0, kResume));
    } catch (const std::exception& e) {
        err = e.what();
    }
    EXPECT_NE(err.find((dir / "last").string()), std::string::npos) << err;
    EXPECT_NE(err.find("data.protocol/noise_sigma was 0.0, now 0.01"), std::string::npos) << err;
    // The same pairs resume.
    EXPECT_NO_THROW(Train(config, clean, Options(dir, log, 3, kResume)));
    fs::remove_all(dir);
}

// Issue 27: `train --resume` appended onto a torn metrics.csv line (a kill mid-append). The
// expected file is what an uninterrupted run writes (SameSeedGivesTheSameLossCurve: a header
// and one line per epoch, 2 epochs here), every line with the header's number of columns.
TEST_F(SmallTrain, ResumeDropsATornMetricsLine) {
    const fs::path dir = TempDir("torn");
    Train(config, data, Options(dir, log, 10));
    std::ofstream(dir / "metrics.csv", std::ios::app) << "2,0.5,0.";  // no newline: torn
    Train(config, data, Options(dir, log, 0, kResume));
    std::ifstream csv(dir / "metrics.csv");
    std::vector<std::string> lines;
    for (std::string l; std::getline(csv, l);) lines.push_back(l);
    ASSERT_EQ(lines.size(), 3u) << log.str();
    const auto columns = [](const std::string& l) { return std::count(l.begin(), l.end(), ','); };
    for (const auto& l : lines) EXPECT_EQ(columns(l), columns(lines[0])) << l;
    EXPECT_NE(log.str().find("dropped a torn last line"), std::string::npos);
    fs::remove_all(dir);
}

/// The "step" of every row of `dir`'s metrics.csv and of its metrics.jsonl (both must agree).
std::vector<std::int64_t> MetricSteps(const fs::path& dir) {
    std::vector<std::int64_t> csv_steps, jsonl_steps;
    std::ifstream csv(dir / "metrics.csv");
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line.rfind("epoch,step,", 0), 0u) << line;  // the header: step is column 2
    while (std::getline(csv, line)) {
        const auto a = line.find(','), b = line.find(',', a + 1);
        csv_steps.push_back(std::stoll(line.substr(a + 1, b - a - 1)));
    }
    std::ifstream jsonl(dir / "metrics.jsonl");
    while (std::getline(jsonl, line))
        jsonl_steps.push_back(nlohmann::json::parse(line).at("step").get<std::int64_t>());
    EXPECT_EQ(csv_steps, jsonl_steps);
    return csv_steps;
}

/// Every parameter of the checkpoints `a` and `b` is equal.
void ExpectSameWeights(const fs::path& a, const fs::path& b) {
    const auto na = LoadNetFromCheckpoint(a.string());
    const auto nb = LoadNetFromCheckpoint(b.string());
    const auto pb = nb->named_parameters();
    for (const auto& item : na->named_parameters())
        EXPECT_TRUE(torch::equal(item.value(), pb[item.key()])) << item.key();
}

// Issue 55, item 3: the metrics row was written before the checkpoint it describes, so a save
// that failed (a full disk) after it left a row of a step no checkpoint holds, and the resumed
// run listed that epoch twice (1, 2, 2, 3, 4). The state such a run leaves: a checkpoint of
// step 10 and rows of steps 10 and 20. Expected: the resumed run drops the row of step 20 and
// ends with the rows an uninterrupted run writes, steps 10 and 20, once each.
TEST_F(SmallTrain, ResumeDropsMetricsRowsBeyondTheCheckpoint) {
    const fs::path dir = TempDir("rows_beyond");
    Train(config, data, Options(dir, log, 10));
    ASSERT_EQ(MetricSteps(dir), (std::vector<std::int64_t>{10}));
    std::string csv_row, json_row;
    {
        std::ifstream csv(dir / "metrics.csv");
        std::getline(csv, csv_row);
        std::getline(csv, csv_row);
        std::ifstream jsonl(dir / "metrics.jsonl");
        std::getline(jsonl, json_row);
    }
    const auto third = csv_row.find(',', csv_row.find(',') + 1);
    std::ofstream(dir / "metrics.csv", std::ios::app) << "2,20" << csv_row.substr(third) << "\n";
    nlohmann::json j = nlohmann::json::parse(json_row);
    j["epoch"] = 2;
    j["step"] = 20;
    std::ofstream(dir / "metrics.jsonl", std::ios::app) << j.dump() << "\n";
    Train(config, data, Options(dir, log, 0, kResume));
    EXPECT_EQ(MetricSteps(dir), (std::vector<std::int64_t>{10, 20})) << log.str();
    EXPECT_NE(log.str().find("dropped 1 row(s) after the checkpoint's step 10"), std::string::npos)
        << log.str();
    fs::remove_all(dir);
}

// Issue 55, items 2 and 3: `train` killed while saving last/ (here: after every step of the
// save of step 20, REGBENCH_TEST_KILL_SAVE_AT) left only last.tmp, which a plain rerun deleted
// and --resume did not find. Expected for every step: a plain rerun is refused (a run is
// there), --resume recovers the checkpoint and ends where an uninterrupted run ends (the same
// weights), and the metrics list steps 10 and 20 once each: the row of step 20 is written only
// once its checkpoint is saved, or from the checkpoint when the kill came in between.
TEST_F(SmallTrain, AKillDuringACheckpointSaveResumesToTheUninterruptedRun) {
    const fs::path whole = TempDir("kill_whole");
    Train(config, data, Options(whole, log));
    for (int k = 1; k <= 7; ++k) {
        SCOPED_TRACE("killed after step " + std::to_string(k) + " of the save of step 20");
        const fs::path dir = TempDir("kill_" + std::to_string(k));
        Train(config, data, Options(dir, log, 10));
        const int status = regbench::testing::RunSaveKilledAtStep(k, [&] {
            std::ostringstream quiet;
            Train(config, data, Options(dir, quiet, 0, kResume));
        });
        ASSERT_EQ(regbench::testing::NotKilledBySigkill(status), "");
        // A row only ever describes a saved state: none for step 20 before last/ holds it.
        EXPECT_EQ(MetricSteps(dir), (std::vector<std::int64_t>{10}));
        const std::string plain =
            regbench::testing::ErrorOf([&] { Train(config, data, Options(dir, log)); });
        EXPECT_NE(plain.find("already holds a run"), std::string::npos) << plain;
        std::ostringstream resumed;
        Train(config, data, Options(dir, resumed, 0, kResume));
        EXPECT_EQ(MetricSteps(dir), (std::vector<std::int64_t>{10, 20})) << resumed.str();
        EXPECT_FALSE(fs::exists(dir / "last.tmp"));
        EXPECT_FALSE(fs::exists(dir / "last.old"));
        ExpectSameWeights(dir / "last", whole / "last");
        fs::remove_all(dir);
    }
    fs::remove_all(whole);
}

// Issue 55, item 2: a run killed in its first save left only last.tmp, and a plain rerun started
// over and deleted it. Expected: a whole last.tmp (killed after step 4, before its rename) is
// renamed to last/ and the plain rerun refused like any run holding last/ (--resume then goes
// on from step 10); an incomplete one (killed after step 2) holds no checkpoint, is removed
// (said in the log) and the rerun starts.
TEST_F(SmallTrain, AFreshRunRecoversAFirstSaveAKillInterrupted) {
    for (const int k : {2, 4}) {
        SCOPED_TRACE("first save killed after step " + std::to_string(k));
        const fs::path dir = TempDir("first_save_" + std::to_string(k));
        const int status = regbench::testing::RunSaveKilledAtStep(k, [&] {
            std::ostringstream quiet;
            Train(config, data, Options(dir, quiet, 10));
        });
        ASSERT_EQ(regbench::testing::NotKilledBySigkill(status), "");
        ASSERT_TRUE(fs::exists(dir / "last.tmp"));
        ASSERT_FALSE(fs::exists(dir / "last"));
        std::ostringstream rerun;
        const std::string e =
            regbench::testing::ErrorOf([&] { Train(config, data, Options(dir, rerun, 10)); });
        EXPECT_FALSE(fs::exists(dir / "last.tmp"));
        if (k == 4) {
            EXPECT_NE(e.find("already holds a run (last/)"), std::string::npos) << e;
            EXPECT_NE(rerun.str().find("finished an interrupted save"), std::string::npos)
                << rerun.str();
            std::ostringstream resumed;
            EXPECT_EQ(Train(config, data, Options(dir, resumed, 0, kResume)).steps, 20);
            EXPECT_NE(resumed.str().find("at step 10 of"), std::string::npos) << resumed.str();
        } else {
            EXPECT_EQ(e, "");
            EXPECT_NE(rerun.str().find("an incomplete save"), std::string::npos) << rerun.str();
            EXPECT_TRUE(fs::exists(dir / "last" / "checkpoint.json"));
        }
        fs::remove_all(dir);
    }
}

// Issue 55, item 7: `train --lr 1e18` ended in a raw LibTorch backtrace, and a recipe's NaN lr
// passed "lr <= 0". Expected: a recipe lr outside (0, kMaxLearningRate = 1] is refused naming
// lr; 1 itself is accepted.
TEST(Train, RecipeLearningRateOutsideItsRangeIsRefused) {
    for (const double lr : {1e18, 1.5, std::nan(""), 0.0, -1.0}) {
        const std::string e =
            regbench::testing::ErrorOf([&] { TrainConfigFromJson({{"lr", lr}}); });
        EXPECT_NE(e.find("need lr in (0, 1]"), std::string::npos) << lr << ": " << e;
    }
    EXPECT_EQ(TrainConfigFromJson({{"lr", 1.0}}).lr, 1.0);
}

// A run limited by --max-steps printed the LR plan's step count and an ETA to the plan's end
// (found 2026-12-04: `--max-steps 576` of a 2,560-step plan showed "ETA 0h58m" with 3 steps
// left). Expected, by hand: the line names the stop step and the last line's ETA is zero.
TEST(Train, AShortBudgetPlanSpendsMostStepsAtTheBaseLr) {
    // Issue 41 item 7: 142 planned steps of a 640-step recipe (milestones 75/450, 150/450,
    // 200/450, gamma 0.1). Before, the milestones were fractions of the 142 steps, so from
    // step ceil(142 * 200/450) = 64 on the LR was 1e-6: 78 of 142 steps. Now (by hand) milestone
    // m moves to 1 - (1 - m) * 142/640: 0.8151, 0.8521, 0.8767 of 142 -> steps 116, 121, 125.
    TrainConfig c;
    std::int64_t base = 0, floor = 0;
    for (std::int64_t k = 0; k < 142; ++k) {
        const double lr = MultistepLearningRate(c, k, 142, 640);
        base += lr == c.lr;
        floor += std::abs(lr - 1e-6) < 1e-18;
    }
    EXPECT_EQ(base, 116);
    EXPECT_EQ(floor, 142 - 125);
    EXPECT_DOUBLE_EQ(MultistepLearningRate(c, 120, 142, 640), 1e-4);
    // A run planned as long as its recipe keeps the recipe's milestones: 75/450 of 450 = 75.
    EXPECT_DOUBLE_EQ(MultistepLearningRate(c, 74, 450, 450), 1e-3);
    EXPECT_DOUBLE_EQ(MultistepLearningRate(c, 75, 450, 450), 1e-4);
    EXPECT_DOUBLE_EQ(MultistepLearningRate(c, 200, 450, 450), 1e-3 * 1e-3);
}

TEST(Train, ProgressCountsDownToMaxSteps) {
    torch::set_num_threads(1);
    const TrainData data = testing::SyntheticData(4, 160, 2);
    std::ostringstream log;
    const fs::path dir = TempDir("progress");
    TrainOptions o = Options(dir, log);
    o.max_steps = 3;
    o.progress_seconds = 0;
    Train(SmallRecipe("deepgmr-orig-xyz"), data, o);  // a plan of 20 steps
    EXPECT_NE(log.str().find("step 3/20 (stops at 3) lr"), std::string::npos) << log.str();
    const std::string last = log.str().substr(log.str().rfind("step 3/20"));
    EXPECT_NE(last.find("ETA 0h00m00s"), std::string::npos) << last;
    fs::remove_all(dir);
}

// Issue 27 item 2/3: a symbolic link pre-placed at RUN/metrics.csv made a fresh `train`
// truncate the file it pointed to (found by hand: `ln -s ../victim.txt t/metrics.csv`, then
// `regbench train --out t` left victim.txt holding the CSV header). Expected: refused naming
// metrics.csv before any step, and the target keeps the bytes written here.
TEST_F(SmallTrain, RefusesALinkAtAMetricsFileAndLeavesItsTarget) {
    for (const char* name : {"metrics.csv", "metrics.jsonl"}) {
        const fs::path dir = TempDir(std::string("link_") + name);
        fs::create_directories(dir);
        const fs::path victim = dir.string() + ".victim";
        std::ofstream(victim) << "victim bytes\n";
        fs::create_symlink(victim, dir / name);
        try {
            Train(config, data, Options(dir, log, 1));
            ADD_FAILURE() << name << ": a link at the metrics file was accepted";
        } catch (const std::runtime_error& e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("symbolic link"), std::string::npos) << e.what();
        }
        std::ifstream in(victim);
        const std::string bytes((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
        EXPECT_EQ(bytes, "victim bytes\n") << name;
        EXPECT_FALSE(fs::exists(dir / "last")) << name << ": trained through the link";
        fs::remove_all(dir);
        fs::remove(victim);
    }
}

/// Environment override of a knob of the CI training below (for re-measuring the margin with
/// other seeds or settings without rebuilding); unset: the default.
double Knob(const char* name, double fallback) {
    const char* v = std::getenv(name);
    return v != nullptr && *v != '\0' ? std::atof(v) : fallback;
}

double ThreadCpuSeconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The issue's acceptance test "a 2-minute training in CI lowers validation MAE(R) well below the
// identity floor": a fixed number of steps (not a wall-clock budget, so the result does not
// depend on the machine's load) of a small DeepGMR (the paper's variant, DGCNN -> CONV3, at
// d = 64, J = 16, k = 10) on the synthetic partial pairs of synthetic_pairs.hpp (bumpy
// ellipsoids of 256 points, 70% crops, motions of up to 45 degrees per Euler axis and 0.5 per
// axis), one thread, seeded. Identity floor = the identity's mean MAE(R) on the same validation
// pairs. Measured on the development VM (docs/learned-methods.md, "CI training test"): ratios
// 0.533 / 0.465 / 0.508 for seeds 1 / 2 / 3, about 44 s of thread CPU each, hence the bound 0.7.
// The REGBENCH_TRAIN_CI_* variables re-measure other seeds or settings without a rebuild.
// Runs as CTest networks_train_ci, label "train" (tests/CMakeLists.txt).
TEST(TrainCi, ShortTrainingLowersValidationMaeRWellBelowTheIdentity) {
    torch::set_num_threads(1);
    const auto seed = static_cast<std::uint64_t>(Knob("REGBENCH_TRAIN_CI_SEED", 1));
    const auto points = static_cast<Eigen::Index>(Knob("REGBENCH_TRAIN_CI_POINTS", 256));
    const double max_deg = Knob("REGBENCH_TRAIN_CI_DEG", 45);
    const auto steps = static_cast<int>(Knob("REGBENCH_TRAIN_CI_STEPS", 60));
    const int val_pairs = 24;
    nlohmann::json config = NamedConfig("deepgmr-small");
    config["emb_dims"] = static_cast<int>(Knob("REGBENCH_TRAIN_CI_EMB", 64));
    config["head_hidden"] = config["emb_dims"];
    config["clusters"] = static_cast<int>(Knob("REGBENCH_TRAIN_CI_J", 16));
    config["dgcnn_k"] = static_cast<int>(Knob("REGBENCH_TRAIN_CI_K", 10));
    config["train"]["lr"] = Knob("REGBENCH_TRAIN_CI_LR", 1e-3);
    config["train"]["weight_decay"] = 0.0;
    config["train"]["schedule"] = "constant";
    config["train"]["batch"] = static_cast<int>(Knob("REGBENCH_TRAIN_CI_BATCH", 8));
    config["train"]["epochs"] = 1;
    config["train"]["pairs_per_epoch"] = steps * config["train"]["batch"].get<int>();
    TrainData data;
    data.train_pair = [seed, points, max_deg](std::uint64_t k) {
        return testing::SyntheticPair(seed, k, points, max_deg);
    };
    for (int i = 0; i < val_pairs; ++i) {
        data.validation.push_back(testing::SyntheticPair(seed + 1000, i, points, max_deg));
    }
    std::ostringstream log;
    const fs::path dir = TempDir("ci");
    TrainOptions options = Options(dir, log, steps);
    options.seed = seed;
    const double cpu0 = ThreadCpuSeconds();
    const TrainSummary s = Train(config, data, options);
    const double cpu = ThreadCpuSeconds() - cpu0;
    fs::remove_all(dir);
    ASSERT_EQ(s.steps, steps);
    ASSERT_FALSE(s.epochs.empty());
    const EpochMetrics& last = s.epochs.back();
    const double ratio = last.mae_r / last.identity_mae_r;
    std::cout << "train-ci: seed " << seed << " points " << points << " max_deg " << max_deg
              << " steps " << steps << " config " << config.dump() << "\ntrain-ci: val MAE(R) "
              << last.mae_r << " deg, identity " << last.identity_mae_r << " deg, ratio " << ratio
              << ", first loss " << s.step_losses.front() << " last " << s.step_losses.back()
              << ", thread CPU " << cpu << " s\n";
    EXPECT_LT(ratio, 0.7);
}

}  // namespace
}  // namespace regbench::networks
