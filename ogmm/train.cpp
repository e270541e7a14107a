#include "ogmm/train.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/metrics.hpp"
#include "core/options.hpp"
#include "ogmm/checkpoint.hpp"
#include "ogmm/zoo.hpp"

namespace regbench::ogmm {
namespace fs = std::filesystem;

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(TrainConfig,
                                                lr,
                                                weight_decay,
                                                batch,
                                                epochs,
                                                pairs_per_epoch,
                                                schedule,
                                                milestones,
                                                lr_gamma,
                                                plateau_patience,
                                                min_lr)

nlohmann::json ToJson(const TrainConfig& c) { return c; }

TrainConfig TrainConfigFromJson(const nlohmann::json& j) {
    // Unknown keys (a misspelt key in a recipe) and wrong types are errors naming the key.
    const auto c = ParseOptions<TrainConfig>(j, "train config");
    if (c.lr <= 0 || c.batch < 1 || c.epochs < 1 || c.pairs_per_epoch < c.batch) {
        throw std::invalid_argument(
            "train config: need lr > 0, batch >= 1, epochs >= 1 and "
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
            {"mae_r_icp", m.mae_r_refined},
            {"mae_t_icp", m.mae_t_refined},
            {"ccd_icp", m.ccd_refined},
            {"identity_mae_r", m.identity_mae_r},
            {"seconds", m.seconds}};
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

/// Validation pass: loss and metrics with and without refinement.
EpochMetrics Validate(RegistrationNet& net,
                      const std::vector<TrainSample>& val,
                      int batch,
                      const torch::Device& device,
                      const RefineFn& refine,
                      std::uint64_t seed) {
    EpochMetrics m;
    if (val.empty()) return m;
    net.eval();
    torch::NoGradGuard no_grad;
    SeedTorch(seed, ~0ULL);
    double loss_sum = 0.0;
    std::size_t batches = 0;
    double sum[7] = {0, 0, 0, 0, 0, 0, 0};
    for (std::size_t start = 0; start < val.size(); start += batch) {
        const std::size_t end = std::min(val.size(), start + batch);
        const std::vector<TrainSample> part(val.begin() + start, val.begin() + end);
        const PairBatch b = Collate(part, device);
        const NetOutput out = net.Forward(b);
        loss_sum += net.Loss(b, out).at("total").item<double>();
        ++batches;
        for (std::size_t i = 0; i < part.size(); ++i) {
            const TrainSample& s = part[i];
            const Transform T = ToTransform(out.T[i]);
            const PairMetrics pm = ComputeMetrics(s.T_gt, T, s.source, s.target);
            sum[0] += pm.mae_r;
            sum[1] += pm.mae_t;
            sum[2] += pm.ccd;
            sum[6] += MotionMetrics(s.T_gt, Transform::Identity()).mae_r;
            if (refine) {
                const PairMetrics pr =
                    ComputeMetrics(s.T_gt, refine(s.source, s.target, T), s.source, s.target);
                sum[3] += pr.mae_r;
                sum[4] += pr.mae_t;
                sum[5] += pr.ccd;
            }
        }
    }
    const double n = static_cast<double>(val.size());
    m.val_loss = loss_sum / static_cast<double>(batches);
    m.mae_r = sum[0] / n;
    m.mae_t = sum[1] / n;
    m.ccd = sum[2] / n;
    m.identity_mae_r = sum[6] / n;
    if (refine) {
        m.mae_r_refined = sum[3] / n;
        m.mae_t_refined = sum[4] / n;
        m.ccd_refined = sum[5] / n;
    }
    return m;
}

/// What the trainer must remember across --resume besides weights and optimizer.
struct TrainerState {
    std::int64_t step = 0;
    double elapsed_seconds = 0.0;  ///< wall seconds over all sessions
    double best_mae_r = std::numeric_limits<double>::infinity();
    double plateau_best = std::numeric_limits<double>::infinity();
    int plateau_bad = 0;
    double plateau_scale = 1.0;
    double epoch_loss_sum = 0.0;
    std::int64_t epoch_loss_steps = 0;
};

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(TrainerState,
                                                step,
                                                elapsed_seconds,
                                                best_mae_r,
                                                plateau_best,
                                                plateau_bad,
                                                plateau_scale,
                                                epoch_loss_sum,
                                                epoch_loss_steps)

/// Infinite bests (nothing validated yet) are written as null, JSON having no infinity.
nlohmann::json ToJson(const TrainerState& s) { return s; }

/// A null (an infinite best) or a key absent from an older checkpoint keeps the default.
TrainerState TrainerStateFromJson(nlohmann::json j) {
    if (!j.contains("step")) throw std::invalid_argument("trainer state: no 'step'");
    for (auto it = j.begin(); it != j.end();) it = it->is_null() ? j.erase(it) : std::next(it);
    return j.get<TrainerState>();
}

/// LR of the next step. multistep: base x gamma^(milestones passed by `progress`).
double LearningRate(const TrainConfig& c, const TrainerState& s, double progress) {
    if (c.schedule == "multistep") {
        double lr = c.lr;
        for (double m : c.milestones) {
            if (progress >= m) lr *= c.lr_gamma;
        }
        return lr;
    }
    if (c.schedule == "plateau") return std::max(c.lr * s.plateau_scale, c.min_lr);
    return c.lr;
}

void SetLearningRate(torch::optim::Adam& opt, double lr) {
    for (auto& group : opt.param_groups()) {
        static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
    }
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
    std::ofstream(dir / "metrics.csv", std::ios::app) << CsvLine(m, /*header=*/false);
    std::ofstream jsonl(dir / "metrics.jsonl", std::ios::app);
    jsonl << ToJson(m).dump() << "\n";
}

}  // namespace

std::vector<Transform> Predict(RegistrationNet& net,
                               const std::vector<TrainSample>& samples,
                               int batch,
                               const torch::Device& device) {
    net.eval();
    torch::NoGradGuard no_grad;
    std::vector<Transform> out;
    for (std::size_t start = 0; start < samples.size(); start += batch) {
        const std::size_t end = std::min(samples.size(), start + batch);
        const PairBatch b = Collate(
            std::vector<TrainSample>(samples.begin() + start, samples.begin() + end), device);
        const NetOutput o = net.Forward(b);
        for (int64_t i = 0; i < o.T.size(0); ++i) out.push_back(ToTransform(o.T[i]));
    }
    return out;
}

TrainSummary Train(const nlohmann::json& config,
                   const TrainData& data,
                   const TrainOptions& options) {
    std::ostream& log = options.log != nullptr ? *options.log : std::cerr;
    if (!data.train_pair) throw std::invalid_argument("Train: no training data source");
    if (options.out_dir.empty()) throw std::invalid_argument("Train: no output directory");
    const TrainConfig tc = TrainConfigFromJson(config.value("train", nlohmann::json::object()));
    if (options.device != "cpu" && options.device != "cuda") {
        throw std::invalid_argument("--device must be cpu or cuda, got '" + options.device + "'");
    }
    if (options.device == "cuda" && !torch::cuda::is_available()) {
        throw std::runtime_error("--device cuda: this LibTorch build sees no CUDA device");
    }
    const torch::Device device(options.device == "cuda" ? torch::kCUDA : torch::kCPU);
    torch::set_num_threads(std::max(1, options.threads));

    const fs::path dir(options.out_dir);
    const fs::path last = dir / "last";
    const fs::path best = dir / "best";
    if (!options.resume && fs::exists(last)) {
        throw std::runtime_error("output directory " + dir.string() +
                                 " already holds a run (last/); pass --resume or another --out");
    }
    fs::create_directories(dir);

    torch::manual_seed(options.seed);  // deterministic initial weights
    std::shared_ptr<RegistrationNet> net = MakeNetFromConfig(config);
    net->to(device);
    torch::optim::Adam opt(net->parameters(),
                           torch::optim::AdamOptions(tc.lr).weight_decay(tc.weight_decay));
    TrainerState state;
    if (options.resume) {
        if (!fs::exists(last)) {
            throw std::runtime_error("--resume: " + last.string() + " does not exist");
        }
        const nlohmann::json j = LoadCheckpoint(last.string(), *net, &opt);
        if (j.contains("config") && j.at("config").value("train", nlohmann::json()) !=
                                        config.value("train", nlohmann::json())) {
            log << "train: note: the training recipe differs from the one in " << last.string()
                << "; continuing with the new one\n";
        }
        state = TrainerStateFromJson(j.at("trainer"));
        log << "train: resumed " << last.string() << " at step " << state.step << "\n";
    } else {
        std::ofstream(dir / "metrics.csv") << CsvLine({}, /*header=*/true);
        std::ofstream(dir / "metrics.jsonl");
    }

    const std::int64_t steps_per_epoch = tc.pairs_per_epoch / tc.batch;
    const std::int64_t total_steps = steps_per_epoch * tc.epochs;
    const double budget = options.minutes * 60.0;
    const int val_batch = options.val_batch > 0 ? options.val_batch : tc.batch;
    const auto session_start = Clock::now();
    const double elapsed_before = state.elapsed_seconds;
    const auto elapsed = [&] {
        return elapsed_before + std::chrono::duration<double>(Clock::now() - session_start).count();
    };
    TrainSummary summary;
    double last_validation_seconds = 0.0;
    double step_seconds = 0.0;
    auto last_progress = Clock::now();
    std::int64_t steps_this_session = 0;

    const auto checkpoint_meta = [&](const EpochMetrics* m) {
        state.elapsed_seconds = elapsed();
        nlohmann::json meta = {{"model", config.value("name", std::string())},
                               {"config", config},
                               {"data", data.provenance},
                               {"steps", state.step},
                               {"epoch", static_cast<double>(state.step) / steps_per_epoch},
                               {"seed", options.seed},
                               {"trainer", ToJson(state)},
                               {"run", options.run_info},
                               {"parameters", CountParameters(*net)}};
        if (m != nullptr) meta["metrics"] = ToJson(*m);
        return meta;
    };
    // Validation + checkpoints; called at the end of every epoch and when the run stops early.
    const auto end_epoch = [&] {
        const auto t0 = Clock::now();
        EpochMetrics m =
            Validate(*net, data.validation, val_batch, device, options.refine, options.seed);
        last_validation_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        m.epoch = static_cast<int>((state.step + steps_per_epoch - 1) / steps_per_epoch);
        m.step = state.step;
        m.lr = LearningRate(tc, state, static_cast<double>(state.step) / total_steps);
        m.train_loss =
            state.epoch_loss_steps > 0 ? state.epoch_loss_sum / state.epoch_loss_steps : 0;
        m.seconds = elapsed();
        state.epoch_loss_sum = 0;
        state.epoch_loss_steps = 0;
        if (tc.schedule == "plateau") {
            if (m.val_loss < state.plateau_best * (1 - 1e-4)) {
                state.plateau_best = m.val_loss;
                state.plateau_bad = 0;
            } else if (++state.plateau_bad > tc.plateau_patience) {
                state.plateau_scale *= tc.lr_gamma;
                state.plateau_bad = 0;
            }
        }
        AppendMetrics(dir, m);
        summary.epochs.push_back(m);
        log << "train: validation epoch " << m.epoch << " step " << m.step << ": loss "
            << m.val_loss << ", mae_r " << m.mae_r << " deg (identity " << m.identity_mae_r
            << "), mae_t " << m.mae_t << ", ccd " << m.ccd;
        if (options.refine)
            log << "; with ICP mae_r " << m.mae_r_refined << ", ccd " << m.ccd_refined;
        log << "\n";
        const bool is_best = !data.validation.empty() && m.mae_r < state.best_mae_r;
        if (is_best) state.best_mae_r = m.mae_r;
        SaveCheckpoint(last.string(), *net, checkpoint_meta(&m), &opt);
        if (is_best) SaveCheckpoint(best.string(), *net, checkpoint_meta(&m), nullptr);
    };

    while (state.step < total_steps) {
        if (options.max_steps > 0 && state.step >= options.max_steps) break;
        // Stop while a validation and one more step still fit the budget.
        if (budget > 0 && elapsed() + last_validation_seconds * 1.5 + step_seconds * 2 > budget) {
            summary.budget_exhausted = true;
            break;
        }
        const double progress =
            budget > 0 ? std::max(static_cast<double>(state.step) / total_steps, elapsed() / budget)
                       : static_cast<double>(state.step) / total_steps;
        const double lr = LearningRate(tc, state, progress);
        SetLearningRate(opt, lr);
        const auto t0 = Clock::now();
        std::vector<TrainSample> samples;
        samples.reserve(tc.batch);
        for (int i = 0; i < tc.batch; ++i) {
            samples.push_back(
                data.train_pair(static_cast<std::uint64_t>(state.step) * tc.batch + i));
        }
        const PairBatch batch = Collate(samples, device);
        SeedTorch(options.seed, static_cast<std::uint64_t>(state.step));
        net->train();
        const NetOutput out = net->Forward(batch);
        const LossTerms terms = net->Loss(batch, out);
        const torch::Tensor total = terms.at("total");
        opt.zero_grad();
        const double loss = total.item<double>();
        if (std::isfinite(loss)) {
            total.backward();
            opt.step();
        } else {
            log << "train: step " << state.step << ": non-finite loss, update skipped\n";
        }
        summary.step_losses.push_back(loss);
        state.epoch_loss_sum += std::isfinite(loss) ? loss : 0.0;
        state.epoch_loss_steps += std::isfinite(loss) ? 1 : 0;
        ++state.step;
        ++steps_this_session;
        step_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        const double session = std::chrono::duration<double>(Clock::now() - session_start).count();
        if (std::chrono::duration<double>(Clock::now() - last_progress).count() >=
                options.progress_seconds ||
            state.step == total_steps) {
            last_progress = Clock::now();
            const double rate = steps_this_session * tc.batch / std::max(session, 1e-9);
            double eta = (total_steps - state.step) * tc.batch / std::max(rate, 1e-9);
            if (budget > 0) eta = std::min(eta, std::max(0.0, budget - elapsed()));
            log << "train: epoch " << (state.step - 1) / steps_per_epoch + 1 << "/" << tc.epochs
                << " step " << state.step << "/" << total_steps << " lr " << lr;
            for (const auto& [name, value] : terms)
                log << " " << name << " " << value.item<double>();
            log << " | " << std::fixed << std::setprecision(2) << rate << " pairs/s, ETA "
                << FormatSeconds(eta) << std::defaultfloat << std::setprecision(6) << "\n";
            log.flush();
        }
        if (state.step % steps_per_epoch == 0) end_epoch();
    }
    // A run stopped mid-epoch (budget or max_steps) still ends with a validated checkpoint.
    if (state.epoch_loss_steps > 0 || !fs::exists(last)) end_epoch();
    summary.steps = state.step;
    if (summary.budget_exhausted) {
        log << "train: wall budget of " << options.minutes << " min reached at step " << state.step
            << "; continue with --resume\n";
    }
    return summary;
}

}  // namespace regbench::ogmm
