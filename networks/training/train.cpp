#include "networks/training/train.hpp"

#include <fcntl.h>
#include <unistd.h>

#include "core/memory_policy.hpp"
#include "networks/training/train_batch.hpp"
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <iomanip>
#include <iostream>
#include <iterator>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/atomic_file.hpp"
#include "core/cpu_time.hpp"
#include "core/file_lock.hpp"
#include "core/metrics.hpp"
#include "core/params.hpp"
#include "networks/checkpoint/checkpoint.hpp"
#include "networks/checkpoint/checkpoint_json.hpp"
#include "networks/layers/layers.hpp"
#include "networks/zoo.hpp"

namespace regbench::networks {
namespace fs = std::filesystem;

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(TrainConfig, lr, weight_decay, batch, epochs,
                                                pairs_per_epoch, schedule, milestones, lr_gamma,
                                                plateau_patience, min_lr)

nlohmann::json ToJson(const TrainConfig& c) { return c; }

TrainConfig TrainConfigFromJson(const nlohmann::json& j) {
    // Unknown keys (a misspelt key in a recipe) and wrong types are errors naming the key.
    const auto c = ParseConfig<TrainConfig>(j, "train config");
    // NaN passed "lr <= 0"; 1e18 passed and ended in a LibTorch backtrace once the weights
    // were no longer finite.
    if (!(c.lr > 0 && c.lr <= kMaxLearningRate) || c.batch < 1 || c.epochs < 1 ||
        c.pairs_per_epoch < c.batch) {
        throw std::invalid_argument(
            "train config: need lr in (0, 1], batch >= 1, epochs >= 1 and "
            "pairs_per_epoch >= batch: " +
            ToJson(c).dump());
    }
    if (c.schedule != "multistep" && c.schedule != "plateau" && c.schedule != "constant") {
        throw std::invalid_argument("train config: unknown schedule '" + c.schedule +
                                    "' (known: multistep, plateau, constant)");
    }
    return c;
}

namespace {

/// metrics.csv's columns and metrics.jsonl's keys, in order: listed once for both files.
std::vector<std::pair<const char*, nlohmann::json>> MetricColumns(const EpochMetrics& m) {
    return {{"epoch", m.epoch},
            {"step", m.step},
            {"lr", m.lr},
            {"train_loss", m.train_loss},
            {"val_loss", m.val_loss},
            {"mae_r", m.mae_r},
            {"mae_t", m.mae_t},
            {"ccd", m.ccd},
            {"recall", m.recall},
            {"mae_r_icp", m.mae_r_refined},
            {"mae_t_icp", m.mae_t_refined},
            {"ccd_icp", m.ccd_refined},
            {"recall_icp", m.recall_refined},
            {"identity_mae_r", m.identity_mae_r},
            {"seconds", m.seconds},
            {"cpu_seconds", m.cpu_seconds}};
}

}  // namespace

nlohmann::json ToJson(const EpochMetrics& m) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& [key, value] : MetricColumns(m)) j[key] = value;
    return j;
}

PairBatch Collate(const std::vector<TrainSample>& samples, const torch::Device& device) {
    if (samples.empty()) throw std::invalid_argument("Collate: no samples");
    const auto n = samples[0].source.rows();
    const auto m = samples[0].target.rows();
    const auto b = static_cast<int64_t>(samples.size());
    const bool overlap =
        samples[0].source_overlap.size() == n && samples[0].target_overlap.size() == m;
    torch::Tensor src = torch::empty({b, n, 3}, torch::kDouble);
    torch::Tensor tgt = torch::empty({b, m, 3}, torch::kDouble);
    torch::Tensor T = torch::empty({b, 4, 4}, torch::kDouble);
    torch::Tensor so = torch::zeros({b, n}, torch::kDouble);
    torch::Tensor to = torch::zeros({b, m}, torch::kDouble);
    for (int64_t i = 0; i < b; ++i) {
        const TrainSample& s = samples[i];
        if (s.source.rows() != n || s.target.rows() != m) {
            throw std::invalid_argument("Collate: sample " + std::to_string(i) + " has " +
                                        std::to_string(s.source.rows()) + "+" +
                                        std::to_string(s.target.rows()) + " points, sample 0 " +
                                        std::to_string(n) + "+" + std::to_string(m));
        }
        std::copy(s.source.data(), s.source.data() + 3 * n, src[i].data_ptr<double>());
        std::copy(s.target.data(), s.target.data() + 3 * m, tgt[i].data_ptr<double>());
        const Eigen::Matrix<double, 4, 4, Eigen::RowMajor> Tr = s.T_gt;
        std::copy(Tr.data(), Tr.data() + 16, T[i].data_ptr<double>());
        if (overlap) {
            std::copy(s.source_overlap.data(), s.source_overlap.data() + n,
                      so[i].data_ptr<double>());
            std::copy(s.target_overlap.data(), s.target_overlap.data() + m,
                      to[i].data_ptr<double>());
        }
    }
    PairBatch batch;
    const auto f = torch::TensorOptions().dtype(torch::kFloat).device(device);
    batch.source = src.to(f);
    batch.target = tgt.to(f);
    batch.T_gt = T.to(f);
    if (overlap) {
        batch.source_overlap = so.to(f);
        batch.target_overlap = to.to(f);
    }
    return batch;
}

namespace {

using Clock = std::chrono::steady_clock;

// The recall of validation: the fraction of pairs with MAE(R) below 1 degree and MAE(t) below
// 0.1, the thresholds `regbench report` uses by default (--recall-r 1 --recall-t 0.1).
constexpr double kRecallMaeRDeg = 1.0;
constexpr double kRecallMaeT = 0.1;
// A wall budget stops the run while one more validation (with this margin over the last one's
// time) and this many more steps still fit, so a budget never ends without a checkpoint.
constexpr double kValidationTimeMargin = 1.5;
constexpr double kStepsKeptInReserve = 2.0;
// plateau: a validation loss must improve by this relative amount to count as a gain
// (PyTorch's ReduceLROnPlateau default threshold, mode "rel").
constexpr double kPlateauRelativeGain = 1e-4;
// A fresh run with a wall budget and no explicit length times this many steps, then plans its
// LR schedule over the steps that fit the budget (frozen in the checkpoint from then on).
constexpr std::int64_t kPlanningSteps = 3;

Transform ToTransform(const torch::Tensor& T) {
    const torch::Tensor c = T.detach().to(torch::kCPU, torch::kDouble).contiguous();
    Eigen::Matrix<double, 4, 4, Eigen::RowMajor> m;
    std::copy(c.data_ptr<double>(), c.data_ptr<double>() + 16, m.data());
    return m;
}

/// splitmix64: independent per-step seeds from (seed, step).
std::uint64_t Mix(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

void SeedTorch(std::uint64_t seed, std::uint64_t step) {
    torch::manual_seed(Mix(seed ^ Mix(step)) & 0x7fffffffffffULL);
}

/// Sums of the validation metrics over pairs.
struct MetricSums {
    double mae_r = 0, mae_t = 0, ccd = 0, recall = 0;
    void Add(const PairMetrics& m) {
        mae_r += m.mae_r;
        mae_t += m.mae_t;
        ccd += m.ccd;
        recall += (m.mae_r < kRecallMaeRDeg && m.mae_t < kRecallMaeT) ? 1.0 : 0.0;
    }
};

/// Validation pass: loss and metrics with and without refinement.
EpochMetrics Validate(RegistrationNet& net, const std::vector<TrainSample>& val, int batch,
                      const torch::Device& device, const RefineFn& refine, std::uint64_t seed) {
    EpochMetrics m;
    if (val.empty()) return m;
    net.eval();
    torch::NoGradGuard no_grad;
    SeedTorch(seed, ~0ULL);
    double loss_sum = 0.0, identity_sum = 0.0;
    std::size_t batches = 0;
    MetricSums net_sums, refined_sums;
    for (std::size_t start = 0; start < val.size(); start += batch) {
        const std::size_t end = std::min(val.size(), start + batch);
        const std::vector<TrainSample> part(val.begin() + start, val.begin() + end);
        const PairBatch b = Collate(part, device);
        const NetOutput out = net.Forward(b);
        loss_sum += net.Loss(b, out).at("total").item<double>();
        ++batches;
        for (std::size_t i = 0; i < part.size(); ++i) {
            const TrainSample& s = part[i];
            const Transform T = ToTransform(out.T[static_cast<int64_t>(i)]);
            net_sums.Add(ComputeMetrics(s.T_gt, T, s.source, s.target));
            identity_sum += MotionMetrics(s.T_gt, Transform::Identity()).mae_r;
            if (refine) {
                refined_sums.Add(
                    ComputeMetrics(s.T_gt, refine(s.source, s.target, T), s.source, s.target));
            }
        }
    }
    const double n = static_cast<double>(val.size());
    m.val_loss = loss_sum / static_cast<double>(batches);
    m.mae_r = net_sums.mae_r / n;
    m.mae_t = net_sums.mae_t / n;
    m.ccd = net_sums.ccd / n;
    m.recall = net_sums.recall / n;
    m.identity_mae_r = identity_sum / n;
    if (refine) {
        m.mae_r_refined = refined_sums.mae_r / n;
        m.mae_t_refined = refined_sums.mae_t / n;
        m.ccd_refined = refined_sums.ccd / n;
        m.recall_refined = refined_sums.recall / n;
    }
    return m;
}

/// What the trainer must remember across --resume besides weights and optimizer.
struct TrainerState {
    std::int64_t step = 0;
    /// Steps the LR schedule spans, fixed when the run starts (the recipe's epochs, or what fits
    /// a wall budget); a resumed run keeps it, so its LRs are those of an uninterrupted run.
    std::int64_t planned_steps = 0;
    double lr = 0.0;               ///< LR of the last step taken
    double elapsed_seconds = 0.0;  ///< wall seconds over all sessions
    double cpu_seconds = 0.0;      ///< process CPU seconds over all sessions
    std::int64_t pairs_seen = 0;   ///< training pairs consumed (steps x batch)
    double best_mae_r = std::numeric_limits<double>::infinity();
    double plateau_best = std::numeric_limits<double>::infinity();
    int plateau_bad = 0;
    double plateau_scale = 1.0;
    double epoch_loss_sum = 0.0;
    std::int64_t epoch_loss_steps = 0;
};

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(TrainerState, step, planned_steps, lr,
                                                elapsed_seconds, cpu_seconds, pairs_seen,
                                                best_mae_r, plateau_best, plateau_bad,
                                                plateau_scale, epoch_loss_sum, epoch_loss_steps)

/// Infinite bests (nothing validated yet) are written as null, JSON having no infinity.
nlohmann::json ToJson(const TrainerState& s) { return s; }

/// Appends `text` to `path` (created when absent; emptied first when `truncate`) with checked
/// writes. Never through a link: a symbolic or hard link pre-placed at metrics.csv made a fresh
/// run truncate the file it pointed to. Throws naming the file (ENOSPC, EFBIG, a link).
void WriteMetricsFile(const fs::path& path, const std::string& text, bool truncate) {
    RequireRegularOrAbsent(path.string(), "metrics file");
    const int fd = ::open(
        path.c_str(),
        O_WRONLY | O_CREAT | O_APPEND | O_NOFOLLOW | O_CLOEXEC | (truncate ? O_TRUNC : 0), 0644);
    if (fd < 0) {
        throw std::runtime_error(path.string() +
                                 ": cannot open metrics file: " + std::strerror(errno));
    }
    try {
        WriteAllOrThrow(fd, text, path.string());
    } catch (...) {
        ::close(fd);
        throw;
    }
    if (::close(fd) != 0) {
        throw std::runtime_error(path.string() + ": write failed: " + std::strerror(errno));
    }
}

/// The text of metrics file `path`; nullopt when there is none, and a path that is not a
/// regular file throws (RequireRegularOrAbsent).
std::optional<std::string> ReadMetricsFile(const fs::path& path) {
    std::error_code ec;
    if (!fs::exists(fs::symlink_status(path, ec))) return std::nullopt;
    RequireRegularOrAbsent(path.string(), "metrics file");
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// A null (an infinite best) or a key absent from an older checkpoint keeps the default.
/// A kill during an append leaves the metrics file's last line without its newline; the
/// resumed run's first line would be glued onto it. Cut the file after its last newline
/// (the lost line's epoch is validated again) and say so.
void DropTornLastLine(const fs::path& path, std::ostream& log) {
    const std::optional<std::string> read = ReadMetricsFile(path);
    if (!read) return;
    const std::string& text = *read;
    if (text.empty() || text.back() == '\n') return;
    const std::size_t keep = text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1;
    std::error_code ec;
    fs::resize_file(path, keep, ec);
    if (ec)
        throw std::runtime_error(path.string() + ": cannot drop a torn last line: " + ec.message());
    log << "train: dropped a torn last line of " << path.string() << " (" << text.size() - keep
        << " bytes, cut by an interrupted write)\n";
}

/// The metrics files of a resumed run hold exactly the rows of its checkpoint's past: a row
/// of a step after the checkpoint's (left when a save failed or was killed after its row was
/// written, as regbench wrote them until issue 55) is dropped, and the checkpoint's own row,
/// missing when a kill came between the save and the append, is written from its
/// checkpoint.json "metrics". Both are said in the log.
void KeepMetricsOfCheckpoint(const fs::path& dir, const nlohmann::json& checkpoint,
                             std::ostream& log) {
    const std::int64_t step = checkpoint.value("steps", std::int64_t{0});
    const nlohmann::json row = checkpoint.value("metrics", nlohmann::json());
    const bool has_row = row.is_object() && row.value("step", std::int64_t{-1}) == step;
    for (const bool csv : {true, false}) {
        const fs::path path = dir / (csv ? "metrics.csv" : "metrics.jsonl");
        const std::optional<std::string> text = ReadMetricsFile(path);
        if (!text) continue;
        std::istringstream lines(*text);
        std::string kept, line;
        std::int64_t last_step = -1;
        int dropped = 0;
        int step_column = -1;
        for (bool first = true; std::getline(lines, line); first = false) {
            std::int64_t row_step = -1;
            if (csv && first) {  // the header
                std::istringstream cells(line);
                std::string cell;
                for (int c = 0; std::getline(cells, cell, ','); ++c)
                    if (cell == "step") step_column = c;
                kept += line + "\n";
                continue;
            }
            try {
                if (csv) {
                    std::istringstream cells(line);
                    std::string cell;
                    for (int c = 0; std::getline(cells, cell, ',') && c <= step_column; ++c)
                        if (c == step_column) row_step = std::stoll(cell);
                } else {
                    row_step = nlohmann::json::parse(line).at("step").get<std::int64_t>();
                }
            } catch (const std::exception&) {
                throw std::runtime_error(path.string() + ": a row without a readable step: " +
                                         line.substr(0, 80));
            }
            if (row_step > step) {
                ++dropped;
                continue;
            }
            last_step = std::max(last_step, row_step);
            kept += line + "\n";
        }
        const bool add = has_row && last_step < step;
        if (add) {
            if (csv) {
                std::string cells;
                for (const auto& [key, value] : MetricColumns(EpochMetrics{})) {
                    (void)value;
                    cells += (cells.empty() ? "" : ",") + row.at(key).dump();
                }
                kept += cells + "\n";
            } else {
                kept += row.dump() + "\n";
            }
        }
        if (dropped == 0 && !add) continue;
        WriteFileAtomic(path.string(), kept);
        log << "train: " << path.string() << ": ";
        if (dropped > 0) {
            log << "dropped " << dropped << " row(s) after the checkpoint's step " << step;
        }
        if (add) {
            log << (dropped > 0 ? "; " : "") << "wrote the checkpoint's row of step " << step;
        }
        log << "\n";
    }
}

/// Every counter is checked as written: a count must be a whole number in [0, 2^53] (a step of
/// 1e30 became -9.2e18 through the int64 conversion and disabled --max-steps), every other
/// number finite and >= 0. Throws std::invalid_argument naming the key and the value.
TrainerState TrainerStateFromJson(nlohmann::json j) {
    // networks/checkpoint/checkpoint_json.cpp: every counter, named when refused.
    CheckTrainerStateJson(j);
    for (auto it = j.begin(); it != j.end();) it = it->is_null() ? j.erase(it) : std::next(it);
    return j.get<TrainerState>();
}

std::string FormatSeconds(double s) {
    std::ostringstream o;
    const long t = static_cast<long>(s);
    o << t / 3600 << "h" << std::setw(2) << std::setfill('0') << (t / 60) % 60 << "m"
      << std::setw(2) << t % 60 << "s";
    return o.str();
}

/// One CSV line: the column names, or one epoch's values (JSON numbers: exact round trip).
std::string CsvLine(const EpochMetrics& m, bool header) {
    std::string line;
    for (const auto& [key, value] : MetricColumns(m)) {
        line += (line.empty() ? "" : ",") + (header ? std::string(key) : value.dump());
    }
    return line + "\n";
}

void AppendMetrics(const fs::path& dir, const EpochMetrics& m) {
    WriteMetricsFile(dir / "metrics.csv", CsvLine(m, /*header=*/false), /*truncate=*/false);
    WriteMetricsFile(dir / "metrics.jsonl", ToJson(m).dump() + "\n", /*truncate=*/false);
}

/// Set by SIGINT / SIGTERM while a Trainer runs: the run ends after the current step with a
/// validated checkpoint, so `--resume` loses nothing.
volatile std::sig_atomic_t g_stop_requested = 0;
extern "C" void RequestStop(int) { g_stop_requested = 1; }

/// Installs RequestStop for SIGINT and SIGTERM for the guard's lifetime.
class StopSignalGuard {
public:
    StopSignalGuard() {
        g_stop_requested = 0;
        previous_int_ = std::signal(SIGINT, RequestStop);
        previous_term_ = std::signal(SIGTERM, RequestStop);
    }
    ~StopSignalGuard() {
        std::signal(SIGINT, previous_int_);
        std::signal(SIGTERM, previous_term_);
    }
    StopSignalGuard(const StopSignalGuard&) = delete;
    StopSignalGuard& operator=(const StopSignalGuard&) = delete;

private:
    void (*previous_int_)(int) = SIG_DFL;
    void (*previous_term_)(int) = SIG_DFL;
};

/// The training loop in named steps: Resume (or start), then Step until the plan, the budget,
/// --max-steps or a stop signal ends the run, with Validate + Checkpoint at every epoch's end.
/// Batches are built by a second thread one step ahead (the data stream depends on the step
/// only, so the order of work does not change a single value).
class Trainer {
public:
    Trainer(const nlohmann::json& config, const TrainData& data, const TrainOptions& options);
    TrainSummary Run();

private:
    void Start();
    void Resume();
    void RecoverCheckpoints();
    void RefuseOtherTrainingPairs(const nlohmann::json& checkpoint, const fs::path& last) const;
    std::future<PairBatch> Prefetch(std::int64_t step) const;
    double Step(const PairBatch& batch);
    void EndEpoch();
    void Checkpoint(const EpochMetrics& m);
    /// The step this run ends at: the LR plan's last, or --max-steps when that comes first.
    std::int64_t LastStep() const;
    bool ShouldStop() const;
    void PlanForBudget();
    double LearningRate() const;
    void LogProgress(const LossTerms& terms);
    double Elapsed() const;
    double CpuSeconds() const;

    const nlohmann::json config_;
    const TrainData& data_;
    const TrainOptions& options_;
    std::ostream& log_;
    const TrainConfig recipe_;
    const torch::Device device_;
    const fs::path dir_;
    const std::int64_t steps_per_epoch_;
    const double budget_seconds_;
    std::shared_ptr<RegistrationNet> net_;
    std::unique_ptr<torch::optim::Adam> opt_;
    TrainerState state_;
    TrainSummary summary_;
    Clock::time_point session_start_ = Clock::now();
    double session_cpu_start_ = ProcessCpuSeconds();
    double elapsed_before_ = 0.0, cpu_before_ = 0.0;
    double last_validation_seconds_ = 0.0, step_seconds_ = 0.0;
    Clock::time_point last_progress_ = Clock::now();
    std::int64_t steps_this_session_ = 0;
};

torch::Device ParseDevice(const std::string& device) {
    if (device != "cpu" && device != "cuda") {
        throw std::invalid_argument("--device must be cpu or cuda, got '" + device + "'");
    }
    if (device == "cuda" && !torch::cuda::is_available()) {
        throw std::runtime_error("--device cuda: this LibTorch build sees no CUDA device");
    }
    return torch::Device(device == "cuda" ? torch::kCUDA : torch::kCPU);
}

Trainer::Trainer(const nlohmann::json& config, const TrainData& data, const TrainOptions& options)
    : config_(config),
      data_(data),
      options_(options),
      log_(options.log != nullptr ? *options.log : std::cerr),
      recipe_(TrainConfigFromJson(config.value("train", nlohmann::json::object()))),
      device_(ParseDevice(options.device)),
      dir_(options.out_dir),
      steps_per_epoch_(recipe_.pairs_per_epoch / recipe_.batch),
      budget_seconds_(options.minutes * 60.0) {
    if (!data.train_pair) throw std::invalid_argument("Train: no training data source");
    if (options.out_dir.empty()) throw std::invalid_argument("Train: no output directory");
    torch::set_num_threads(std::max(1, options.threads));
    RetainFreedMemory();
    torch::manual_seed(options.seed);  // deterministic initial weights
    net_ = MakeNetFromConfig(config);
    net_->to(device_);
    opt_ = std::make_unique<torch::optim::Adam>(
        net_->parameters(),
        torch::optim::AdamOptions(recipe_.lr).weight_decay(recipe_.weight_decay));
}

void Trainer::Start() {
    // A save of last/ a kill interrupted is finished or undone first, so a run whose last/ was
    // between its renames is refused below like any other (a fresh run used to delete it).
    RecoverCheckpoints();
    if (fs::exists(fs::symlink_status(dir_ / "last"))) {
        throw std::runtime_error("output directory " + dir_.string() +
                                 " already holds a run (last/); pass --resume or another --out");
    }
    if (!options_.init_from.empty()) {
        LoadCheckpoint(options_.init_from, *net_);  // refuses another model config by name
        log_ << "train: initial weights from " << options_.init_from << "\n";
    }
    fs::create_directories(dir_);
    WriteMetricsFile(dir_ / "metrics.csv", CsvLine({}, /*header=*/true), /*truncate=*/true);
    WriteMetricsFile(dir_ / "metrics.jsonl", "", /*truncate=*/true);
    state_.planned_steps = steps_per_epoch_ * recipe_.epochs;
}

/// The pairs a run learns from are part of its curve: resuming a noise-free run without
/// `--no-jitter`, or on another dataset, would carry on silently on other data. The checkpoint's
/// `data` (the provenance it was trained with) must agree on the datasets, the splits and the
/// pair protocol; the first difference is named with both values.
void Trainer::RefuseOtherTrainingPairs(const nlohmann::json& checkpoint,
                                       const fs::path& last) const {
    if (!checkpoint.contains("data") || !checkpoint.at("data").is_object()) return;
    nlohmann::json was, now;
    for (const char* key : {"dataset", "split", "val_split", "protocol"}) {
        was[key] = checkpoint.at("data").value(key, nlohmann::json());
        now[key] = data_.provenance.value(key, nlohmann::json());
    }
    const nlohmann::json patch = nlohmann::json::diff(was, now);
    if (patch.empty()) return;
    const std::string path = patch[0].at("path").get<std::string>();  // "/protocol/noise_sigma"
    const nlohmann::json::json_pointer at(path);
    throw std::runtime_error("--resume: " + last.string() + " was trained on other pairs (data." +
                             path.substr(1) + " was " +
                             (was.contains(at) ? was.at(at).dump() : "absent") + ", now " +
                             (now.contains(at) ? now.at(at).dump() : "absent") +
                             "): pass the data options the run started with (its "
                             "checkpoint.json 'data'; e.g. --no-jitter, --pairing)");
}

void Trainer::RecoverCheckpoints() {
    // A save a kill interrupted is finished or undone (a whole folder is never discarded), and
    // said so.
    for (const char* name : {"last", "best"}) {
        const std::string done = RecoverCheckpointFolder((dir_ / name).string());
        if (!done.empty()) log_ << "train: " << done << "\n";
    }
}

void Trainer::Resume() {
    const fs::path last = dir_ / "last";
    RecoverCheckpoints();
    if (!fs::exists(last))
        throw std::runtime_error("--resume: " + last.string() + " does not exist");
    const nlohmann::json j = LoadCheckpoint(last.string(), *net_, opt_.get());
    if (j.contains("config") && j.at("config").value("train", nlohmann::json()) !=
                                    config_.value("train", nlohmann::json())) {
        log_ << "train: note: the training recipe differs from the one in " << last.string()
             << "; continuing with the new one\n";
    }
    RefuseOtherTrainingPairs(j, last);
    try {
        state_ = TrainerStateFromJson(j.at("trainer"));
    } catch (const std::exception& e) {
        throw std::runtime_error("checkpoint file " + (last / "checkpoint.json").string() + ": " +
                                 e.what());
    }
    if (state_.planned_steps <= 0) state_.planned_steps = steps_per_epoch_ * recipe_.epochs;
    for (const char* name : {"metrics.csv", "metrics.jsonl"}) DropTornLastLine(dir_ / name, log_);
    KeepMetricsOfCheckpoint(dir_, j, log_);
    elapsed_before_ = state_.elapsed_seconds;
    cpu_before_ = state_.cpu_seconds;
    log_ << "train: resumed " << last.string() << " at step " << state_.step << " of "
         << state_.planned_steps << " planned\n";
}

double Trainer::Elapsed() const {
    return elapsed_before_ + std::chrono::duration<double>(Clock::now() - session_start_).count();
}

double Trainer::CpuSeconds() const {
    return cpu_before_ + ProcessCpuSeconds() - session_cpu_start_;
}

/// multistep: MultistepLearningRate; plateau: base x the factor validations have cut it by;
/// constant: base.
double Trainer::LearningRate() const {
    if (recipe_.schedule == "multistep") {
        return MultistepLearningRate(recipe_, state_.step, state_.planned_steps,
                                     steps_per_epoch_ * recipe_.epochs);
    }
    if (recipe_.schedule == "plateau") {
        return std::max(recipe_.lr * state_.plateau_scale, recipe_.min_lr);
    }
    return recipe_.lr;
}

/// With options.plan_to_budget, after the first kPlanningSteps steps of a fresh run: the
/// schedule spans the steps that fit the budget at the measured time a step, never more than the
/// recipe's steps. From then on the plan is fixed (and stored in every checkpoint).
void Trainer::PlanForBudget() {
    if (!options_.plan_to_budget || budget_seconds_ <= 0 || state_.step != kPlanningSteps ||
        steps_this_session_ != kPlanningSteps) {
        return;
    }
    const double per_step = Elapsed() / static_cast<double>(kPlanningSteps);
    const auto fit = static_cast<std::int64_t>(budget_seconds_ / std::max(per_step, 1e-9));
    if (fit < state_.planned_steps) {
        state_.planned_steps = std::max(fit, kPlanningSteps + 1);
        const std::int64_t recipe_steps = steps_per_epoch_ * recipe_.epochs;
        log_ << "train: LR schedule planned over " << state_.planned_steps
             << " steps, what fits the " << options_.minutes << "-minute budget at " << per_step
             << " s a step (the recipe has " << recipe_steps << ", about "
             << std::ceil(per_step * static_cast<double>(recipe_steps) / 60.0)
             << " min at this rate)";
        if (recipe_.schedule == "multistep") {
            // Where the compressed plan cuts the LR (MultistepLearningRate).
            log_ << "; LR cut by " << recipe_.lr_gamma << " at steps";
            for (double m : recipe_.milestones) {
                const double f =
                    static_cast<double>(state_.planned_steps) / static_cast<double>(recipe_steps);
                log_ << " "
                     << std::ceil((1.0 - (1.0 - m) * f) *
                                  static_cast<double>(state_.planned_steps));
            }
        }
        log_ << "\n";
    }
}

std::future<PairBatch> Trainer::Prefetch(std::int64_t step) const {
    // The new thread takes the process's torch thread count on its first parallel op.
    return std::async(std::launch::async, [this, step] {
        std::vector<TrainSample> samples;
        samples.reserve(static_cast<std::size_t>(recipe_.batch));
        for (int i = 0; i < recipe_.batch; ++i) {
            samples.push_back(data_.train_pair(static_cast<std::uint64_t>(step) *
                                                   static_cast<std::uint64_t>(recipe_.batch) +
                                               static_cast<std::uint64_t>(i)));
        }
        return Collate(samples, device_);
    });
}

/// One optimizer step: seeded forward, loss, backward and Adam at the schedule's LR; a
/// non-finite loss skips the update (logged).
double Trainer::Step(const PairBatch& batch) {
    state_.lr = LearningRate();
    for (auto& group : opt_->param_groups()) {
        static_cast<torch::optim::AdamOptions&>(group.options()).lr(state_.lr);
    }
    SeedTorch(options_.seed, static_cast<std::uint64_t>(state_.step));
    net_->train();
    const NetOutput out = net_->Forward(batch);
    const LossTerms terms = net_->Loss(batch, out);
    const torch::Tensor total = terms.at("total");
    opt_->zero_grad();
    const double loss = total.item<double>();
    if (std::isfinite(loss)) {
        total.backward();
        opt_->step();
    } else {
        log_ << "train: step " << state_.step << ": non-finite loss, update skipped\n";
    }
    summary_.step_losses.push_back(loss);
    state_.epoch_loss_sum += std::isfinite(loss) ? loss : 0.0;
    state_.epoch_loss_steps += std::isfinite(loss) ? 1 : 0;
    state_.pairs_seen += recipe_.batch;
    ++state_.step;
    ++steps_this_session_;
    LogProgress(terms);
    return loss;
}

void Trainer::LogProgress(const LossTerms& terms) {
    if (std::chrono::duration<double>(Clock::now() - last_progress_).count() <
            options_.progress_seconds &&
        state_.step != LastStep()) {
        return;
    }
    last_progress_ = Clock::now();
    const double session = std::chrono::duration<double>(Clock::now() - session_start_).count();
    const double rate =
        static_cast<double>(steps_this_session_ * recipe_.batch) / std::max(session, 1e-9);
    double eta =
        static_cast<double>((LastStep() - state_.step) * recipe_.batch) / std::max(rate, 1e-9);
    if (budget_seconds_ > 0) eta = std::min(eta, std::max(0.0, budget_seconds_ - session));
    log_ << "train: epoch " << (state_.step - 1) / steps_per_epoch_ + 1 << " step " << state_.step
         << "/" << state_.planned_steps;
    if (LastStep() < state_.planned_steps) log_ << " (stops at " << LastStep() << ")";
    log_ << " lr " << state_.lr;
    for (const auto& [name, value] : terms) log_ << " " << name << " " << value.item<double>();
    log_ << " | " << std::fixed << std::setprecision(2) << rate << " pairs/s, ETA "
         << FormatSeconds(eta) << std::defaultfloat << std::setprecision(6) << "\n";
    log_.flush();
}

std::int64_t Trainer::LastStep() const {
    return options_.max_steps > 0 ? std::min(options_.max_steps, state_.planned_steps)
                                  : state_.planned_steps;
}

bool Trainer::ShouldStop() const {
    if (state_.step >= LastStep()) return true;
    if (g_stop_requested != 0) return true;
    const double session = std::chrono::duration<double>(Clock::now() - session_start_).count();
    return budget_seconds_ > 0 && session + last_validation_seconds_ * kValidationTimeMargin +
                                          step_seconds_ * kStepsKeptInReserve >
                                      budget_seconds_;
}

/// Validation, the plateau schedule's bookkeeping, metrics files and checkpoints.
void Trainer::EndEpoch() {
    const auto t0 = Clock::now();
    const int val_batch = options_.val_batch > 0 ? options_.val_batch : recipe_.batch;
    EpochMetrics m =
        Validate(*net_, data_.validation, val_batch, device_, options_.refine, options_.seed);
    last_validation_seconds_ = std::chrono::duration<double>(Clock::now() - t0).count();
    m.epoch = static_cast<int>((state_.step + steps_per_epoch_ - 1) / steps_per_epoch_);
    m.step = state_.step;
    m.lr = state_.lr;
    m.train_loss = state_.epoch_loss_steps > 0
                       ? state_.epoch_loss_sum / static_cast<double>(state_.epoch_loss_steps)
                       : 0;
    m.seconds = Elapsed();
    m.cpu_seconds = CpuSeconds();
    state_.epoch_loss_sum = 0;
    state_.epoch_loss_steps = 0;
    if (recipe_.schedule == "plateau") {
        if (m.val_loss < state_.plateau_best * (1 - kPlateauRelativeGain)) {
            state_.plateau_best = m.val_loss;
            state_.plateau_bad = 0;
        } else if (++state_.plateau_bad > recipe_.plateau_patience) {
            state_.plateau_scale *= recipe_.lr_gamma;
            state_.plateau_bad = 0;
        }
    }
    summary_.epochs.push_back(m);
    log_ << "train: validation epoch " << m.epoch << " step " << m.step << ": loss " << m.val_loss
         << ", mae_r " << m.mae_r << " deg (identity " << m.identity_mae_r << "), mae_t " << m.mae_t
         << ", ccd " << m.ccd << ", recall " << m.recall;
    if (options_.refine)
        log_ << "; with ICP mae_r " << m.mae_r_refined << ", ccd " << m.ccd_refined;
    if (!data_.validation.empty() && m.mae_r >= m.identity_mae_r) {
        log_ << "; WORSE THAN THE IDENTITY (network alone)";
    }
    log_ << "\n";
    // The metrics row describes the saved state: written once the checkpoint is (a full disk
    // or a kill in between leaves a checkpoint without its row, which --resume writes from the
    // checkpoint, never a row without its checkpoint).
    Checkpoint(m);
    AppendMetrics(dir_, m);
}

void Trainer::Checkpoint(const EpochMetrics& m) {
    state_.elapsed_seconds = Elapsed();
    state_.cpu_seconds = CpuSeconds();
    const bool is_best = !data_.validation.empty() && m.mae_r < state_.best_mae_r;
    if (is_best) state_.best_mae_r = m.mae_r;
    nlohmann::json meta = {
        {"model", config_.value("name", std::string())},
        {"config", config_},
        {"data", data_.provenance},
        {"steps", state_.step},
        {"epoch", static_cast<double>(state_.step) / static_cast<double>(steps_per_epoch_)},
        {"pairs_seen", state_.pairs_seen},
        {"cpu_seconds", state_.cpu_seconds},
        {"wall_seconds", state_.elapsed_seconds},
        {"seed", options_.seed},
        {"trainer", ToJson(state_)},
        {"run", options_.run_info},
        {"parameters", CountParameters(*net_)},
        {"metrics", ToJson(m)},
        // The network alone does worse than not moving the source at all on validation.
        {"worse_than_identity", !data_.validation.empty() && m.mae_r >= m.identity_mae_r}};
    SaveCheckpoint((dir_ / "last").string(), *net_, meta, opt_.get());
    if (is_best) SaveCheckpoint((dir_ / "best").string(), *net_, meta, nullptr);
}

TrainSummary Trainer::Run() {
    if (options_.resume) {
        Resume();
    } else {
        Start();
    }
    const StopSignalGuard signals;
    std::future<PairBatch> next = Prefetch(state_.step);
    while (!ShouldStop()) {
        const auto t0 = Clock::now();
        const PairBatch batch = next.get();
        next = Prefetch(state_.step + 1);
        Step(batch);
        step_seconds_ = std::chrono::duration<double>(Clock::now() - t0).count();
        PlanForBudget();
        if (state_.step % steps_per_epoch_ == 0) EndEpoch();
    }
    next.wait();
    // A run stopped mid-epoch (budget, max_steps, a signal) still ends with a validated
    // checkpoint.
    if (state_.epoch_loss_steps > 0 || !fs::exists(dir_ / "last")) EndEpoch();
    summary_.steps = state_.step;
    summary_.budget_exhausted = budget_seconds_ > 0 && state_.step < LastStep();
    if (g_stop_requested != 0) {
        log_ << "train: stopped by a signal at step " << state_.step
             << " with a checkpoint; continue with --resume\n";
    } else if (summary_.budget_exhausted) {
        log_ << "train: wall budget of " << options_.minutes << " min reached at step "
             << state_.step << "; continue with --resume\n";
    }
    return summary_;
}

}  // namespace

double MultistepLearningRate(const TrainConfig& c, std::int64_t step, std::int64_t planned_steps,
                             std::int64_t recipe_steps) {
    const double planned = static_cast<double>(std::max<std::int64_t>(1, planned_steps));
    const double f =
        std::min(1.0, planned / static_cast<double>(std::max<std::int64_t>(1, recipe_steps)));
    const double progress = static_cast<double>(step) / planned;
    double lr = c.lr;
    for (double m : c.milestones) {
        if (progress >= (f < 1.0 ? 1.0 - (1.0 - m) * f : m)) lr *= c.lr_gamma;
    }
    return lr;
}

TrainSummary Train(const nlohmann::json& config, const TrainData& data,
                   const TrainOptions& options) {
    return Trainer(config, data, options).Run();
}

}  // namespace regbench::networks
