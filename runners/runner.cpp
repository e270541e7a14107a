#include "runners/runner.hpp"

#include <fcntl.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "baselines/library_versions.hpp"
#include "core/atomic_file.hpp"
#include "core/cpu_time.hpp"
#include "core/file_lock.hpp"
#include "core/threads.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_hash.hpp"
#include "runners/interrupt.hpp"
#include "runners/isolated_call.hpp"
#include "runners/progress.hpp"
#include "runners/registry.hpp"
#include "runners/resume.hpp"
#include "runners/scale_guard.hpp"

namespace regbench {
namespace {

std::string RowKey(std::size_t pair, const std::string& method) {
    return std::to_string(pair) + "\t" + method;
}

/// Shell-quotes one argument for the printed resume command.
std::string ShellQuote(const std::string& s) {
    std::string out = "'";
    for (const char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

/// The command that continues this run (printed on SIGINT/SIGTERM).
std::string ResumeCommand(const RunOptions& o) {
    std::string names;
    nlohmann::json params = nlohmann::json::object();
    for (const auto& m : o.methods) {
        names += (names.empty() ? "" : ",") + m.name;
        params[m.name] = m.params;
    }
    std::string cmd = "regbench run --pairs " + ShellQuote(o.pairs_path) + " --methods " +
                      ShellQuote(names) + " --params " + ShellQuote(params.dump()) + " --out " +
                      ShellQuote(o.out_path);
    if (o.shard_count > 1) {
        cmd += " --shard " + std::to_string(o.shard_index) + "/" + std::to_string(o.shard_count);
    }
    // --resume refuses rows of another timeout or thread count: repeat them exactly (%.17g
    // round-trips the double; std::to_string would print 1e-7 as 0.000000).
    if (o.timeout_seconds > 0) {
        char timeout[64];
        std::snprintf(timeout, sizeof(timeout), "%.17g", o.timeout_seconds);
        cmd += std::string(" --timeout ") + timeout;
    }
    if (o.threads_per_call != 1) cmd += " --threads " + std::to_string(o.threads_per_call);
    if (o.max_points != RunOptions{}.max_points) {
        cmd += " --max-points " + std::to_string(o.max_points);
    }
    if (o.downsample) cmd += " --downsample";
    // --resume refuses rows scored in another convention: repeat the one this run used.
    cmd += std::string(" --euler ") + ToString(o.euler);
    return cmd + " --jobs " + std::to_string(o.jobs) + " --resume";
}

/// The streamed `<out>.part`: one checked write(2) per row, so every row that was reported
/// written is in the file even if the process is killed right after.
class PartFile {
public:
    /// Replaces whatever plain file is at `path` by a new, empty one: the old one is unlinked
    /// (never truncated through a link) and the new one created with O_EXCL | O_NOFOLLOW, so a
    /// link placed there between the check and the open is refused, not followed.
    explicit PartFile(const std::string& path) : path_(path) {
        RequireRegularOrAbsent(path, "partial results file");
        if (::unlink(path.c_str()) != 0 && errno != ENOENT) {
            throw std::runtime_error(path + ": cannot replace: " + strerror(errno));
        }
        fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
        if (fd_ < 0) throw std::runtime_error(path + ": cannot write: " + strerror(errno));
    }
    ~PartFile() {
        if (fd_ >= 0) ::close(fd_);
    }
    PartFile(const PartFile&) = delete;
    PartFile& operator=(const PartFile&) = delete;
    void Append(const ResultRow& row) { WriteAllOrThrow(fd_, ToJsonLine(row) + "\n", path_); }
    /// fsync + close, checked: a full disk reported only at close is still an error.
    void Close() {
        const int fd = fd_;
        fd_ = -1;
        if (::fsync(fd) != 0 || ::close(fd) != 0) {
            throw std::runtime_error(path_ + ": write failed: " + strerror(errno));
        }
    }

private:
    std::string path_;
    int fd_ = -1;
};

/// A number the method's option field cannot hold exactly (2.5 or -1 into an iteration count,
/// 1e23 into an int) is truncated or wrapped by the JSON binding: compare each given number
/// with the value the method kept and refuse any difference.
void RequireExactNumbers(const std::string& method, const nlohmann::json& given,
                         const nlohmann::json& kept) {
    if (!given.is_object()) return;
    for (const auto& item : given.items()) {
        if (!item.value().is_number() || !kept.contains(item.key())) continue;
        const nlohmann::json& k = kept.at(item.key());
        const bool sign_flip =
            k.is_number() && (k.get<double>() < 0) != (item.value().get<double>() < 0);
        if (k != item.value() || sign_flip) {
            throw std::invalid_argument(method + ": parameter '" + item.key() + "' cannot be " +
                                        item.value().dump() + " (the option holds " + k.dump() +
                                        "; give a value of its type and range)");
        }
    }
}

}  // namespace

std::vector<MethodSpec> ParseMethodSpecs(const std::string& comma_list,
                                         const nlohmann::json& params_by_method) {
    if (!params_by_method.is_null() && !params_by_method.is_object()) {
        throw std::invalid_argument("--params must be a JSON object keyed by method name");
    }
    std::vector<MethodSpec> specs;
    std::set<std::string> seen;
    std::string list = comma_list;
    if (list == "all") {
        list.clear();
        for (const auto& m : AllMethods()) list += (list.empty() ? "" : ",") + m.name;
    }
    std::stringstream ss(list);
    std::string name;
    while (std::getline(ss, name, ',')) {
        name.erase(0, name.find_first_not_of(" \t"));
        name.erase(name.find_last_not_of(" \t") + 1);
        if (name.empty()) continue;
        if (!seen.insert(name).second)
            throw std::invalid_argument("method '" + name + "' listed twice");
        MethodSpec spec{name, nlohmann::json::object()};
        if (params_by_method.is_object() && params_by_method.contains(name)) {
            spec.params = params_by_method.at(name);
        }
        const nlohmann::json given = spec.params;
        spec.given = given;
        spec.params = CreateMethod(name, spec.params)->Params();  // validates, fills defaults
        RequireExactNumbers(name, given, spec.params);
        specs.push_back(spec);
    }
    if (params_by_method.is_object()) {
        for (const auto& item : params_by_method.items()) {
            if (!seen.count(item.key())) {
                throw std::invalid_argument("--params names method '" + item.key() +
                                            "' which is not in --methods");
            }
        }
    }
    if (specs.empty()) throw std::invalid_argument("no methods given");
    return specs;
}

ResultRow MakeResultRow(std::size_t pair_index, const Pair& pair, const MethodSpec& method,
                        const AlignResult& result, const RowContext& context) {
    ResultRow row;
    row.pair = pair_index;
    row.method = method.name;
    row.params = method.params;
    row.result = result;
    row.status = context.status.value_or(StatusOf(result));
    row.threads = context.threads;
    row.shape = pair.shape;
    row.category = pair.category;
    row.source_overlap_ratio = pair.source_overlap_ratio;
    row.target_overlap_ratio = pair.target_overlap_ratio;
    row.source_points = static_cast<std::size_t>(pair.source.rows());
    row.target_points = static_cast<std::size_t>(pair.target.rows());
    row.euler = context.euler;
    row.metrics = ComputeMetrics(pair.T_gt, result.T_target_source, pair.source, pair.target,
                                 context.euler, context.metric_options);
    row.metrics.overlap_rmse =
        OverlapRmse(pair.T_gt, result.T_target_source, pair.source, pair.source_overlap);
    row.gt_transform = pair.T_gt;
    row.data = context.data;
    row.machine = context.machine;
    return row;
}

DataTag DataTagOf(const std::string& pairs_path, const PairSet& set) {
    DataTag d;
    const nlohmann::json& p = set.provenance;
    d.pairs_file = std::filesystem::path(pairs_path).filename().string();
    d.dataset = p.value("dataset", "unknown");
    d.protocol = p.value("protocol", "unknown");
    d.pairing =
        p.value("pairing", p.value("params", nlohmann::json::object()).value("pairing", "unknown"));
    d.seed = p.value("seed", nlohmann::json());
    d.dataset_sha256 = p.value("dataset_sha256", "");
    d.scale = PairFileScale(pairs_path, set);
    // Hashed on every read, so files written before hashes existed get one too; a stored hash
    // that disagrees means the arrays changed after generation.
    d.content_hash = PairSetContentHash(set);
    const std::string stored = p.value("content_hash", "");
    if (!stored.empty() && stored != d.content_hash) {
        throw std::runtime_error(pairs_path +
                                 ": pairs do not match the content hash stored at "
                                 "generation (" +
                                 stored + " vs " + d.content_hash + "): the file was modified");
    }
    return d;
}

double PairFileScale(const std::string& pairs_path, const PairSet& set) {
    const nlohmann::json scale = set.provenance.value("scale", nlohmann::json(1.0));
    if (!scale.is_number() || !std::isfinite(scale.get<double>()) || scale.get<double>() <= 0.0) {
        throw std::runtime_error(pairs_path + ": provenance scale must be a finite number > 0, got " +
                                 scale.dump());
    }
    return scale.get<double>();
}

MetricOptions PairMetricOptions(const std::string& pairs_path, const PairSet& set,
                                MetricOptions options, bool ccd_clip_given) {
    if (!ccd_clip_given && options.ccd_clip == kCcdClip) {
        options.ccd_clip = kCcdClip * PairFileScale(pairs_path, set);
    }
    return options;
}

namespace {

/// The power of length a parameter's documentation declares for its value: 1 for
/// "[unit-sphere units]", 2 for "[unit-sphere units^2]", 0 otherwise (the unit a method's
/// Fields binding states for `regbench methods`).
int LengthPower(const std::string& doc) {
    if (doc.find("[unit-sphere units^2]") != std::string::npos) return 2;
    if (doc.find("[unit-sphere units]") != std::string::npos) return 1;
    return 0;
}

}  // namespace

std::vector<MethodSpec> PairScaledSpecs(std::vector<MethodSpec> specs, double scale) {
    if (scale == 1.0) return specs;
    const std::set<std::string> registered = [] {
        std::set<std::string> names;
        for (const MethodInfo& m : AllMethods()) names.insert(m.name);
        return names;
    }();
    for (MethodSpec& spec : specs) {
        if (!registered.count(spec.name)) continue;  // an external method: its own business
        const MethodInfo& info = FindMethod(spec.name);
        nlohmann::json params = spec.params;
        bool scaled = false;
        for (const auto& [key, doc] : info.param_docs) {
            const int power = LengthPower(doc);
            if (power == 0 || (spec.given.is_object() && spec.given.contains(key))) continue;
            if (!params.contains(key) || !params[key].is_number() ||
                params[key] != info.defaults.value(key, nlohmann::json())) {
                continue;  // not at its default (e.g. a preset's value): as it is
            }
            params[key] = params[key].get<double>() * std::pow(scale, power);
            scaled = true;
        }
        // The per-pair size rule (`scale_rule` auto) compares the pair's size with
        // `scale_rule_radius`, a length scaled above with the others, so it picks on the scaled
        // copy of a pair the unit pair's factor.
        if (!scaled) continue;
        spec.params = CreateMethod(spec.name, params)->Params();  // validates
    }
    return specs;
}

std::uint64_t BenchmarkSeed(const PairSet& set) {
    const nlohmann::json& seed = set.provenance.value("seed", nlohmann::json());
    if (seed.is_number_unsigned()) return seed.get<std::uint64_t>();
    if (seed.is_number_integer()) return static_cast<std::uint64_t>(seed.get<std::int64_t>());
    return 0;
}

namespace {

void ValidateRunOptions(const RunOptions& options) {
    if (options.methods.empty()) throw std::invalid_argument("no methods to run");
    if (options.jobs < 1) throw std::invalid_argument("--jobs must be >= 1");
    if (options.threads_per_call < 1) throw std::invalid_argument("--threads must be >= 1");
    if (options.shard_count < 1 || options.shard_index < 0 ||
        options.shard_index >= options.shard_count) {
        throw std::invalid_argument("--shard must be i/n with 0 <= i < n");
    }
    if (options.out_path.empty()) throw std::invalid_argument("--out is required");
    CheckMetricOptions(options.metric_options);
    for (const auto& m : AllMethods()) {
        if (options.external_methods.count(m.name)) {
            throw std::invalid_argument(
                "'" + m.name + "' is a registered method; name the external one otherwise");
        }
    }
}

/// The pair indices of this run's shard: every shard_count-th pair from shard_index.
std::vector<std::size_t> ShardPairs(std::size_t num_pairs, const RunOptions& options) {
    std::vector<std::size_t> indices;
    for (std::size_t k = 0; k < num_pairs; ++k) {
        if (static_cast<int>(k % static_cast<std::size_t>(options.shard_count)) ==
            options.shard_index) {
            indices.push_back(k);
        }
    }
    return indices;
}

/// The rows an interrupted run already wrote (with --resume) and their (pair, method) keys.
struct Resumed {
    std::vector<ResultRow> rows;
    std::set<std::string> done;
};

/// The `timeout` a row records: the --timeout it ran under (0: in-process). Rows written
/// before the key existed ran in-process unless told otherwise, so a missing key reads as 0.
double RowTimeout(const ResultRow& r) {
    const auto it = r.other.find("timeout");
    return it != r.other.end() && it->is_number() ? it->get<double>() : 0.0;
}

bool SameTransform(const Transform& a, const Transform& b) {
    // Rows store doubles through JSON, which round-trips them exactly; the slack only forgives
    // a writer that printed fewer digits, never an edited matrix.
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
            if (!(std::abs(a(r, c) - b(r, c)) <= 1e-12 * std::max(1.0, std::abs(b(r, c))))) {
                return false;
            }
        }
    }
    return true;
}

/// The caller-supplied method named `name`, or null for a registered one.
const ExternalMethod* FindExternal(const RunOptions& options, const std::string& name) {
    const auto it = options.external_methods.find(name);
    return it == options.external_methods.end() ? nullptr : &it->second;
}

/// Refuses a kept row that this run would not have produced: another --timeout, --threads,
/// downsampling (--downsample / --max-points), or ground truth / shape that differ from what
/// the pair file holds now. docs/metrics.md ("What defines a row") lists the fields.
void CheckRowSettings(const ResultRow& r, const RunOptions& options, const PairSet& set) {
    const auto refuse = [&](const std::string& what) {
        throw std::runtime_error(r.origin + ": row was produced under other settings (" + what +
                                 "); resume with the same settings or start a new file");
    };
    if (RowTimeout(r) != options.timeout_seconds) {
        refuse("--timeout " + std::to_string(RowTimeout(r)) + ", this run " +
               std::to_string(options.timeout_seconds));
    }
    if (r.threads != options.threads_per_call) {
        refuse("--threads " + std::to_string(r.threads) + ", this run " +
               std::to_string(options.threads_per_call));
    }
    const Pair& pair = set.pairs.at(r.pair);
    const bool reduce =
        options.downsample &&
        NeedsScaleGuard(GuardedCost(MethodSpec{r.method, r.params}, options), pair,
                        options.max_points);
    nlohmann::json expected = nullptr;
    if (reduce) DownsampleByStride(pair, options.max_points, &expected);
    const auto got = r.other.find("downsampled");
    const nlohmann::json recorded = got != r.other.end() ? *got : nlohmann::json(nullptr);
    if (recorded != expected) {
        refuse("downsampled " + recorded.dump() + ", this run " + expected.dump());
    }
    if (r.gt_transform && !SameTransform(*r.gt_transform, pair.T_gt)) {
        refuse("gt_transform differs from pair " + std::to_string(r.pair) + " of the pair file");
    }
    if (r.shape != pair.shape || r.category != pair.category) {
        refuse("shape '" + r.shape + "' / category '" + r.category + "', the pair file has '" +
               pair.shape + "' / '" + pair.category + "'");
    }
}

/// Reads the kept rows of an interrupted run (its .part file, else the finished output).
/// Every kept row is checked against this run; a foreign row is refused, never mixed.
Resumed LoadResume(const RunOptions& options, const PairSet& set, const std::string& part_path,
                   const RowExpectation& expect) {
    Resumed resumed;
    if (!options.resume) return resumed;
    const bool have_part = std::filesystem::exists(part_path);
    const bool have_out = std::filesystem::exists(options.out_path);
    const std::string& kept = have_part ? part_path : options.out_path;
    if (have_part || have_out) resumed.rows = ReadResumableRows(kept, expect);
    for (const auto& r : resumed.rows) {
        // One file, one convention: resumed rows scored otherwise would split the report.
        if (r.euler != options.euler) {
            throw std::runtime_error(r.origin + ": rows were scored with --euler " +
                                     ToString(r.euler) + "; resume with --euler " +
                                     ToString(r.euler) + " or start a new file");
        }
        CheckRowSettings(r, options, set);
        resumed.done.insert(RowKey(r.pair, r.method));
    }
    return resumed;
}

/// Everything the workers read, fixed for the whole run.
struct RunPlan {
    RunPlan(const RunOptions& o, const PairSet& s) : options(o), set(s) {}
    const RunOptions& options;
    const PairSet& set;
    std::vector<std::size_t> indices;  ///< pairs of this shard
    std::set<std::string> done;        ///< (pair, method) keys resumed from a previous run
    std::uint64_t benchmark_seed = 0;  ///< methods' per-pair RNG streams derive from it
    RowContext row_context;            ///< threads, euler, data and machine tags of every row
};

/// What the workers share while they run: the output and the counters.
struct RunState {
    RunState(PartFile& p, ProgressMeter& m) : part(p), progress(m) {}
    PartFile& part;
    ProgressMeter& progress;
    std::mutex out_mutex;  ///< guards `part`, `error` and the rows_safe increment
    std::atomic<std::size_t> next{0};
    std::atomic<std::size_t> failures{0};
    std::atomic<std::size_t> written{0};
    std::atomic<std::size_t> rows_safe{0};
    std::atomic<bool> stop{false};
    std::exception_ptr error;  ///< first failure in a worker (a write error), rethrown after join
};

/// One (pair, method) call, isolated when a timeout is set, turned into its row.
ResultRow RunCall(const RunPlan& plan, RegistrationMethod& method, const MethodSpec& spec,
                  const AlignContext& context) {
    const RunOptions& options = plan.options;
    const std::size_t k = context.pair_index;
    const Pair& pair = plan.set.pairs[k];
    // Scale guard: an O(N*M) method on a large cloud runs on the recorded stride-downsampled
    // pair; metrics still compare against the full pair.
    nlohmann::json downsampled;
    const ExternalMethod* external = FindExternal(options, spec.name);
    const bool reduce = options.downsample &&
                        NeedsScaleGuard(GuardedCost(spec, options), pair, options.max_points);
    const Pair reduced =
        reduce ? DownsampleByStride(pair, options.max_points, &downsampled) : Pair{};
    const Pair& input = reduce ? reduced : pair;
    const CallOutcome outcome =
        options.timeout_seconds > 0.0
            ? AlignIsolated(method, input, context, options.timeout_seconds,
                            options.threads_per_call, external ? external->fork_hooks : ForkHooks{})
            : AlignInProcess(method, input, context);
    RowContext row_context = plan.row_context;
    row_context.status = outcome.status;
    ResultRow row = MakeResultRow(k, pair, spec, outcome.result, row_context);
    if (reduce) row.other["downsampled"] = downsampled;
    // The points the call had (Tab. 6's `points`): the reduced clouds under --downsample.
    row.source_points = static_cast<std::size_t>(input.source.rows());
    row.target_points = static_cast<std::size_t>(input.target.rows());
    // What defines the row besides method, params and pair: --resume compares it.
    row.other["timeout"] = options.timeout_seconds;
    return row;
}

/// One worker: takes the next pair until none is left or the run stops, runs every method
/// not yet done on it and appends the rows as they come.
void WorkOnPairs(const RunPlan& plan, RunState& state) {
    const RunOptions& options = plan.options;
    // Each worker owns its method instances: methods keep scratch buffers.
    omp_set_num_threads(options.threads_per_call);
    std::vector<std::unique_ptr<RegistrationMethod>> methods;
    for (const auto& spec : options.methods) {
        const ExternalMethod* external = FindExternal(options, spec.name);
        methods.push_back(external ? external->create() : CreateMethod(spec.name, spec.params));
    }
    for (;;) {
        if (state.stop.load()) return;
        const std::size_t i = state.next.fetch_add(1);
        if (i >= plan.indices.size()) return;
        AlignContext context;
        context.seed = plan.benchmark_seed;
        context.pair_index = plan.indices[i];
        context.threads = options.threads_per_call;
        for (std::size_t m = 0; m < methods.size(); ++m) {
            const auto& spec = options.methods[m];
            if (plan.done.count(RowKey(context.pair_index, spec.name))) continue;
            const ResultRow row = RunCall(plan, *methods[m], spec, context);
            if (options.check_interrupt) options.check_interrupt();  // may end the run
            if (row.status != Status::kOk) state.failures.fetch_add(1);
            {
                std::lock_guard<std::mutex> guard(state.out_mutex);
                if (state.stop.load()) return;
                state.part.Append(row);  // throws on a write error: RunWorkers stops the run
                state.rows_safe.fetch_add(1);
            }
            state.written.fetch_add(1);
            state.progress.Advance();
        }
    }
}

/// Runs `jobs` workers (this thread is one of them) until every call is done. An exception
/// must not escape a std::thread (std::terminate): the first one stops all workers and is kept
/// in state.error for the caller to rethrow after they joined.
void RunWorkers(const RunPlan& plan, RunState& state) {
    const auto worker = [&] {
        try {
            WorkOnPairs(plan, state);
        } catch (...) {
            std::lock_guard<std::mutex> guard(state.out_mutex);
            if (!state.error) state.error = std::current_exception();
            state.stop = true;
        }
    };
    const RunOptions& options = plan.options;
    const int jobs =
        std::max(1, std::min<int>(options.jobs, static_cast<int>(plan.indices.size())));
    std::vector<std::thread> threads;
    for (int j = 1; j < jobs; ++j) threads.emplace_back(worker);
    worker();
    for (auto& t : threads) t.join();
}

/// The final file: rows sorted by (pair, method order), so its order does not depend on
/// --jobs; written atomically, then the .part file is removed.
void WriteSortedRows(const RunOptions& options, const std::string& part_path,
                     const RowExpectation& expect) {
    std::vector<ResultRow> all = ReadResumableRows(part_path, expect);
    std::map<std::string, std::size_t> order;
    for (std::size_t m = 0; m < options.methods.size(); ++m) order[options.methods[m].name] = m;
    std::stable_sort(all.begin(), all.end(), [&](const ResultRow& a, const ResultRow& b) {
        return std::make_pair(a.pair, order[a.method]) < std::make_pair(b.pair, order[b.method]);
    });
    std::string text;
    for (const auto& r : all) text += ToJsonLine(r) + "\n";
    WriteFileAtomic(options.out_path, text, {options.pairs_path});
    std::filesystem::remove(part_path);
}

/// The row tags every call of this run shares. The machine's load when the run started is
/// timing provenance: a reader can tell whether wall times were taken on a busy machine
/// (docs/performance.md); so are the CPU model and the library versions the calls ran on
/// (shown in `report`'s timing caption, issue 54).
RowContext RunRowContext(const RunOptions& options, const DataTag& data_tag) {
    const MachineLoad load = ReadMachineLoad();
    RowContext context;
    context.threads = options.threads_per_call;
    context.euler = options.euler;
    context.metric_options = options.metric_options;
    context.data = data_tag;
    context.machine = {{"loadavg", {load.load1, load.load5, load.load15}},
                       {"cores", load.cores},
                       {"jobs", options.jobs},
                       {"cpu", CpuModel()},
                       {"libraries", LibraryVersions()}};
    return context;
}

}  // namespace

std::string PairScaleWarning(const PairSet& set, const MetricOptions& options) {
    std::vector<const PointCloud*> targets;
    for (const auto& p : set.pairs) targets.push_back(&p.target);
    return ScaleWarning(MedianCloudRadius(targets), options);
}

RunSummary RunBenchmark(const RunOptions& given) {
    ValidateRunOptions(given);
    const auto start = std::chrono::steady_clock::now();
    const PairSet set = ReadPairFile(given.pairs_path);  // throws naming the file
    // The default CCD clip in the pair file's units (its `scale`); rows record the clip used.
    RunOptions options = given;
    options.metric_options = PairMetricOptions(given.pairs_path, set, given.metric_options,
                                               given.ccd_clip_given);
    // Length parameters left at their unit-sphere defaults, in the pair file's units too.
    options.methods = PairScaledSpecs(given.methods, PairFileScale(given.pairs_path, set));
    // Select pairs. The scale guard refuses before any output exists (or says what it will
    // downsample).
    RunPlan plan(options, set);
    plan.indices = ShardPairs(set.pairs.size(), options);
    const std::string notice = CheckScale(set, plan.indices, options);
    if (!notice.empty()) std::fprintf(stderr, "[run] %s", notice.c_str());
    const std::string scale = PairScaleWarning(set, options.metric_options);
    if (!scale.empty()) std::fprintf(stderr, "[run] warning: %s\n", scale.c_str());
    const std::string part_path = options.out_path + ".part";
    CheckOutputPath(options.out_path, {options.pairs_path});
    CheckOutputPath(part_path, {options.pairs_path});
    const OutputLock lock(options.out_path);  // one writer per output; names the holder's pid
    // A link (or FIFO) at OUT.part is refused before anything reads or writes through it.
    RequireRegularOrAbsent(part_path, "partial results file");
    // Which data every number came from, carried in every row for the reports.
    const DataTag data_tag = DataTagOf(options.pairs_path, set);
    RowExpectation expect;
    expect.content_hash = data_tag.content_hash;
    expect.num_pairs = set.pairs.size();
    expect.shard_index = options.shard_index;
    expect.shard_count = options.shard_count;
    expect.methods = options.methods;
    expect.metric_options = options.metric_options;
    plan.benchmark_seed = BenchmarkSeed(set);
    plan.row_context = RunRowContext(options, data_tag);

    // Load resume, and rewrite the kept rows so a torn last line from the interrupted run
    // disappears.
    Resumed resumed = LoadResume(options, set, part_path, expect);
    plan.done = std::move(resumed.done);
    PartFile part(part_path);
    for (const auto& r : resumed.rows) part.Append(r);

    // Run workers.
    const std::size_t total_calls = plan.indices.size() * options.methods.size();
    ProgressMeter progress("run", total_calls, options.progress);
    progress.Advance(std::min(plan.done.size(), total_calls));
    RunState state(part, progress);
    state.rows_safe = resumed.rows.size();
    // setenv is not thread-safe: set the process-wide part once, before any worker starts.
    SetOmpThreads(options.threads_per_call);
    std::optional<InterruptNotice> interrupt;
    if (!options.check_interrupt) {
        interrupt.emplace(&state.rows_safe, part_path, ResumeCommand(options));
    }
    RunWorkers(plan, state);
    progress.Finish();
    if (state.error) std::rethrow_exception(state.error);
    part.Close();

    // Write sorted.
    WriteSortedRows(options, part_path, expect);
    RunSummary summary;
    summary.rows_skipped = resumed.rows.size();
    summary.rows_written = state.written.load();
    summary.failures = state.failures.load();
    summary.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
}

}  // namespace regbench
