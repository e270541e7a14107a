#pragma once
// Training loop for every RegistrationNet: Adam, a schedule scaled to the budget, seeded and
// deterministic on CPU, progress on a stream, per-epoch validation (with and without a
// caller-supplied refinement such as ICP) in CSV and JSONL, best and last checkpoints, resume,
// and a wall-clock budget that ends cleanly with a checkpoint. Data comes from callbacks so this
// folder never depends on the dataset or protocol code.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "networks/training/sample.hpp"

namespace regbench::networks {

/// Where training data comes from.
struct TrainData {
    /// Pair `index` of the endless training stream; must depend on the index only (same index,
    /// same pair), so training is deterministic and resumable. Called from one thread.
    std::function<TrainSample(std::uint64_t index)> train_pair;
    std::vector<TrainSample> validation;                   ///< fixed validation pairs
    nlohmann::json provenance = nlohmann::json::object();  ///< stored in checkpoints
};

/// Refinement applied to a network estimate in validation (e.g. Open3D ICP): returns the refined
/// T_target_source.
using RefineFn = std::function<Transform(const PointCloud& source, const PointCloud& target,
                                         const Transform& initial)>;

/// The "train" object of a model config.
/// The largest learning rate a recipe or --lr may set: every family's recipe uses 1e-4 to
/// 1e-3, and a rate above 1 only makes the weights overflow.
constexpr double kMaxLearningRate = 1.0;

struct TrainConfig {
    double lr = 1e-3;                    ///< Adam learning rate
    double weight_decay = 0.0;           ///< Adam (L2) weight decay
    int batch = 8;                       ///< pairs per step (drop_last: every step is full)
    int epochs = 10;                     ///< epochs of `pairs_per_epoch` pairs
    int pairs_per_epoch = 512;           ///< training pairs per epoch (the stream is endless)
    std::string schedule = "multistep";  ///< "multistep" | "plateau" | "constant"
    /// multistep: LR x lr_gamma at these fractions of the run's planned steps (the recipe's
    /// epochs, or what fits a wall budget, see TrainOptions::plan_to_budget).
    std::vector<double> milestones = {75.0 / 450, 150.0 / 450, 200.0 / 450};
    double lr_gamma = 0.1;      ///< multistep / plateau factor
    int plateau_patience = 10;  ///< plateau: epochs without a 1e-4 relative gain before a cut
    double min_lr = 1e-6;       ///< plateau: floor
};
nlohmann::json ToJson(const TrainConfig& c);

/// The multistep schedule's LR at `step` of a run whose LR plan spans `planned_steps` and whose
/// recipe spans `recipe_steps` (its epochs). A run planned as long as its recipe cuts the LR by
/// lr_gamma at each milestone (a fraction of the planned steps). A shorter plan (a wall budget,
/// f = planned / recipe < 1) keeps the recipe's tail after each milestone at f of its length,
/// milestone m moving to 1 - (1 - m) f, so a short run spends most of its steps at the base LR
/// and still ends annealed (142 of 640 steps: 82% at the base LR, not 44%).
double MultistepLearningRate(const TrainConfig& c, std::int64_t step, std::int64_t planned_steps,
                             std::int64_t recipe_steps);

/// Unknown keys or bad values throw std::invalid_argument naming them.
TrainConfig TrainConfigFromJson(const nlohmann::json& j);

struct TrainOptions {
    std::string out_dir;  ///< run directory: last/, best/, metrics.csv, metrics.jsonl
    bool resume = false;  ///< continue from out_dir/last
    /// A fresh run starts from this checkpoint folder's weights (same model config; fresh
    /// optimizer, step 0), e.g. an object-trained model fine-tuned on indoor scans; "" = the
    /// seeded initialisation. Ignored by --resume (the run's own weights continue).
    std::string init_from;
    /// Wall-clock budget of this invocation (0: none); the run ends with a validated checkpoint.
    double minutes = 0.0;
    /// With `minutes` on a fresh run: plan the LR schedule over the steps that fit the budget
    /// (timed on the first steps) when the recipe's steps would not fit. The plan is stored in
    /// the checkpoint; a resumed run keeps it.
    bool plan_to_budget = false;
    std::int64_t max_steps = 0;      ///< stop after this many steps in total; 0 = no limit
    int threads = 1;                 ///< torch intra-op threads
    std::uint64_t seed = 0;          ///< initialisation and per-step seeds
    std::string device = "cpu";      ///< "cpu" | "cuda"
    double progress_seconds = 10.0;  ///< progress line interval
    std::ostream* log = nullptr;     ///< progress stream (null: std::cerr)
    RefineFn refine;                 ///< optional refinement for "with ICP" metrics
    int val_batch = 0;               ///< validation batch (0: the training batch)
    nlohmann::json run_info = nlohmann::json::object();  ///< stored in checkpoints (command...)

    /// The rule both front ends (`regbench train`, `regbench-train-portable`) set
    /// `plan_to_budget` by: a fresh run with a budget and no explicit length (`epochs_given`:
    /// --epochs; or max_steps) plans its LR schedule to what fits the budget.
    bool PlansToBudget(bool epochs_given) const {
        return minutes > 0 && !resume && !epochs_given && max_steps == 0;
    }
};

struct EpochMetrics {
    int epoch = 0;
    std::int64_t step = 0;
    double lr = 0.0;
    double train_loss = 0.0;  ///< mean total loss over the epoch's steps
    double val_loss = 0.0;    ///< mean total loss over the validation pairs
    double mae_r = 0.0;       ///< validation mean MAE(R) [deg], network alone
    double mae_t = 0.0;
    double ccd = 0.0;
    double recall = 0.0;          ///< fraction of pairs with mae_r < 1 deg and mae_t < 0.1
    double mae_r_refined = -1.0;  ///< after `refine` (-1 when none)
    double mae_t_refined = -1.0;
    double ccd_refined = -1.0;
    double recall_refined = -1.0;
    double identity_mae_r = 0.0;  ///< the identity's MAE(R) on the same pairs (the floor)
    double seconds = 0.0;         ///< wall time since the run started (over resumes)
    double cpu_seconds = 0.0;     ///< process CPU time since the run started (over resumes)
};
nlohmann::json ToJson(const EpochMetrics& m);

struct TrainSummary {
    std::int64_t steps = 0;            ///< total steps done (over resumes)
    std::vector<double> step_losses;   ///< total loss of every step run in this call
    std::vector<EpochMetrics> epochs;  ///< validations run in this call
    bool budget_exhausted = false;     ///< --minutes ended the run
};

/// Trains the network `config` describes (zoo config with a "train" object) from scratch, or
/// from out_dir/last when options.resume. Writes out_dir/{last,best}/ checkpoints,
/// metrics.csv and metrics.jsonl. Throws std::runtime_error naming the file or input at fault.
TrainSummary Train(const nlohmann::json& config, const TrainData& data,
                   const TrainOptions& options);


}  // namespace regbench::networks
