#include "runners/runner.hpp"

#include <omp.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/cpu_time.hpp"
#include "core/threads.hpp"
#include "protocols/pair_file.hpp"
#include "protocols/pair_hash.hpp"
#include "runners/progress.hpp"
#include "runners/registry.hpp"

namespace regbench {
namespace {

nlohmann::json AlignResultToJson(const AlignResult& r) {
    return {{"transform", TransformToJson(r.T_target_source)},
            {"iterations", r.iterations},
            {"stop_reason", r.stop_reason},
            {"seconds", r.seconds},
            {"cpu_seconds", r.cpu_seconds},
            {"cpu_scope", r.cpu_scope},
            {"status", ToString(r.status)},
            {"message", r.message},
            {"scale", r.scale},
            {"extra", r.extra}};
}

AlignResult AlignResultFromJson(const nlohmann::json& j) {
    AlignResult r;
    r.T_target_source = TransformFromJson(j.at("transform"));
    r.iterations = j.at("iterations").get<int>();
    r.stop_reason = j.at("stop_reason").get<std::string>();
    r.seconds = j.at("seconds").get<double>();
    r.cpu_seconds = j.value("cpu_seconds", 0.0);
    r.cpu_scope = j.value("cpu_scope", std::string("thread"));
    r.status =
        j.at("status") == ToString(AlignStatus::kOk) ? AlignStatus::kOk : AlignStatus::kFailed;
    r.message = j.at("message").get<std::string>();
    r.scale = j.at("scale").get<double>();
    r.extra = j.at("extra");
    return r;
}

/// Result of one call plus the runner-level status (ok, failed, timeout, crashed).
struct CallOutcome {
    AlignResult result;
    Status status = Status::kOk;
};

Status StatusOf(const AlignResult& r) {
    return r.status == AlignStatus::kOk ? Status::kOk : Status::kFailed;
}

CallOutcome Failure(Status status, const std::string& message, double seconds) {
    CallOutcome out;
    out.result.status = AlignStatus::kFailed;
    out.result.message = message;
    out.result.stop_reason = ToString(status);
    out.result.seconds = seconds;
    out.status = status;
    return out;
}

/// Runs Align in a forked child so a crash or a hang cannot take the run down. The child
/// sends the result as JSON through a pipe; the parent kills it after `timeout` seconds.
CallOutcome AlignIsolated(RegistrationMethod& method,
                          const Pair& pair,
                          const AlignContext& context,
                          double timeout,
                          int threads) {
    int fds[2];
    if (pipe(fds) != 0)
        return Failure(Status::kFailed, "pipe() failed: " + std::string(strerror(errno)), 0);
    const pid_t pid = fork();
    if (pid < 0) {
        close(fds[0]);
        close(fds[1]);
        return Failure(Status::kFailed, "fork() failed: " + std::string(strerror(errno)), 0);
    }
    if (pid == 0) {
        close(fds[0]);
        omp_set_num_threads(threads);
        const std::string payload =
            AlignResultToJson(method.Align(pair.source, pair.target, context)).dump();
        size_t off = 0;
        while (off < payload.size()) {
            const ssize_t n = write(fds[1], payload.data() + off, payload.size() - off);
            if (n <= 0) break;
            off += static_cast<size_t>(n);
        }
        close(fds[1]);
        _exit(0);
    }
    close(fds[1]);
    const auto start = std::chrono::steady_clock::now();
    std::string payload;
    char buf[65536];
    bool timed_out = false;
    for (;;) {
        const double left =
            timeout -
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (left <= 0.0) {
            timed_out = true;
            break;
        }
        pollfd pfd{fds[0], POLLIN, 0};
        const int ready = poll(&pfd, 1, static_cast<int>(std::min(left, 1.0) * 1000.0) + 1);
        if (ready < 0 && errno != EINTR) break;
        if (ready <= 0) continue;
        const ssize_t n = read(fds[0], buf, sizeof(buf));
        if (n <= 0) break;  // EOF: child finished (or died)
        payload.append(buf, static_cast<size_t>(n));
    }
    close(fds[0]);
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (timed_out) kill(pid, SIGKILL);
    int wstatus = 0;
    waitpid(pid, &wstatus, 0);
    if (timed_out) {
        return Failure(Status::kTimeout,
                       method.Name() + ": exceeded timeout of " + std::to_string(timeout) + " s",
                       elapsed);
    }
    if (WIFSIGNALED(wstatus)) {
        return Failure(Status::kCrashed,
                       method.Name() + ": crashed with signal " +
                           std::to_string(WTERMSIG(wstatus)) + " (" + strsignal(WTERMSIG(wstatus)) +
                           ")",
                       elapsed);
    }
    try {
        CallOutcome out;
        out.result = AlignResultFromJson(nlohmann::json::parse(payload));
        out.status = StatusOf(out.result);
        return out;
    } catch (const std::exception& e) {
        return Failure(Status::kCrashed, method.Name() + ": child exited without a result",
                       elapsed);
    }
}

CallOutcome AlignInProcess(RegistrationMethod& method,
                           const Pair& pair,
                           const AlignContext& context) {
    CallOutcome out;
    out.result = method.Align(pair.source, pair.target, context);
    out.status = StatusOf(out.result);
    return out;
}

std::string RowKey(std::size_t pair, const std::string& method) {
    return std::to_string(pair) + "\t" + method;
}

/// Rows already in `<out>.part` from an interrupted run (resume); a torn last line is dropped.
std::vector<ResultRow> ReadPartialRows(const std::string& path) {
    std::vector<ResultRow> rows;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty()) continue;
        try {
            rows.push_back(nlohmann::json::parse(line).get<ResultRow>());
        } catch (const std::exception&) {
            break;  // interrupted mid-write: everything after this is redone
        }
    }
    return rows;
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
        spec.params = CreateMethod(name, spec.params)->Params();  // validates, fills defaults
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

ResultRow MakeResultRow(std::size_t pair_index,
                        const Pair& pair,
                        const MethodSpec& method,
                        const AlignResult& result,
                        const RowContext& context) {
    ResultRow row;
    row.pair = pair_index;
    row.method = method.name;
    row.params = method.params;
    row.transform = result.T_target_source;
    row.seconds = result.seconds;
    row.cpu_seconds = result.cpu_seconds;
    row.cpu_scope = result.cpu_scope;
    row.iterations = result.iterations;
    row.status = context.status.value_or(StatusOf(result));
    row.message = result.message;
    row.stop_reason = result.stop_reason;
    row.scale = result.scale;
    row.extra = result.extra;
    row.threads = context.threads;
    row.shape = pair.shape;
    row.category = pair.category;
    row.source_overlap_ratio = pair.source_overlap_ratio;
    row.target_overlap_ratio = pair.target_overlap_ratio;
    row.euler = context.euler;
    row.metrics =
        ComputeMetrics(pair.T_gt, result.T_target_source, pair.source, pair.target, context.euler);
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

std::uint64_t BenchmarkSeed(const PairSet& set) {
    const nlohmann::json& seed = set.provenance.value("seed", nlohmann::json());
    if (seed.is_number_unsigned()) return seed.get<std::uint64_t>();
    if (seed.is_number_integer()) return static_cast<std::uint64_t>(seed.get<std::int64_t>());
    return 0;
}

RunSummary RunBenchmark(const RunOptions& options) {
    if (options.methods.empty()) throw std::invalid_argument("no methods to run");
    if (options.jobs < 1) throw std::invalid_argument("--jobs must be >= 1");
    if (options.threads_per_call < 1) throw std::invalid_argument("--threads must be >= 1");
    if (options.shard_count < 1 || options.shard_index < 0 ||
        options.shard_index >= options.shard_count) {
        throw std::invalid_argument("--shard must be i/n with 0 <= i < n");
    }
    if (options.out_path.empty()) throw std::invalid_argument("--out is required");
    const auto start = std::chrono::steady_clock::now();
    const PairSet set = ReadPairFile(options.pairs_path);  // throws naming the file

    // Which data every number came from, carried in every row for the reports.
    const DataTag data_tag = DataTagOf(options.pairs_path, set);
    // Methods' per-pair RNG streams derive from the pair file's seed and the pair index.
    // Timing provenance (perf): the machine's load when the run started, so a reader can tell
    // whether wall times were taken on a busy machine (see docs/performance.md).
    const MachineLoad load = ReadMachineLoad();
    const nlohmann::json machine_tag = {{"loadavg", {load.load1, load.load5, load.load15}},
                                        {"cores", load.cores},
                                        {"jobs", options.jobs}};
    const std::uint64_t benchmark_seed = BenchmarkSeed(set);
    std::vector<std::size_t> indices;
    for (std::size_t k = 0; k < set.pairs.size(); ++k) {
        if (static_cast<int>(k % static_cast<std::size_t>(options.shard_count)) ==
            options.shard_index) {
            indices.push_back(k);
        }
    }
    const std::string part_path = options.out_path + ".part";
    std::vector<ResultRow> rows;
    std::set<std::string> done;
    if (options.resume) {
        const bool have_part = std::filesystem::exists(part_path);
        rows = ReadPartialRows(have_part ? part_path : options.out_path);
        for (const auto& r : rows) {
            // One file, one convention: resumed rows scored otherwise would split the report.
            if (r.euler != options.euler) {
                throw std::runtime_error((have_part ? part_path : options.out_path) +
                                         ": rows were scored with --euler " + ToString(r.euler) +
                                         "; resume with --euler " + ToString(r.euler) +
                                         " or start a new file");
            }
            done.insert(RowKey(r.pair, r.method));
        }
    }
    RunSummary summary;
    summary.rows_skipped = rows.size();
    // Rewrite the kept rows so a torn last line from the interrupted run disappears.
    std::ofstream part(part_path, std::ios::trunc);
    if (!part) throw std::runtime_error(part_path + ": cannot write");
    for (const auto& r : rows) part << ToJsonLine(r) << "\n";
    part.flush();

    const std::size_t total_calls = indices.size() * options.methods.size();
    ProgressMeter progress("run", total_calls, options.progress);
    progress.Advance(std::min(done.size(), total_calls));
    std::mutex out_mutex;
    std::atomic<std::size_t> next{0};
    std::atomic<std::size_t> failures{0};
    std::atomic<std::size_t> written{0};

    auto worker = [&] {
        // Each worker owns its method instances: methods keep scratch buffers.
        omp_set_num_threads(options.threads_per_call);
        std::vector<std::unique_ptr<RegistrationMethod>> methods;
        for (const auto& spec : options.methods)
            methods.push_back(CreateMethod(spec.name, spec.params));
        for (;;) {
            const std::size_t i = next.fetch_add(1);
            if (i >= indices.size()) return;
            const std::size_t k = indices[i];
            const Pair& pair = set.pairs[k];
            AlignContext context;
            context.seed = benchmark_seed;
            context.pair_index = k;
            context.threads = options.threads_per_call;
            for (std::size_t m = 0; m < methods.size(); ++m) {
                const auto& spec = options.methods[m];
                if (done.count(RowKey(k, spec.name))) continue;
                CallOutcome outcome =
                    options.timeout_seconds > 0.0
                        ? AlignIsolated(*methods[m], pair, context, options.timeout_seconds,
                                        options.threads_per_call)
                        : AlignInProcess(*methods[m], pair, context);
                RowContext row_context;
                row_context.status = outcome.status;
                row_context.threads = options.threads_per_call;
                row_context.euler = options.euler;
                row_context.data = data_tag;
                row_context.machine = machine_tag;
                const ResultRow row = MakeResultRow(k, pair, spec, outcome.result, row_context);
                if (outcome.status != Status::kOk) failures.fetch_add(1);
                {
                    std::lock_guard<std::mutex> lock(out_mutex);
                    part << ToJsonLine(row) << "\n";
                    part.flush();
                }
                written.fetch_add(1);
                progress.Advance();
            }
        }
    };
    // setenv is not thread-safe: set the process-wide part once, before any worker starts.
    SetOmpThreads(options.threads_per_call);
    const int jobs = std::max(1, std::min<int>(options.jobs, static_cast<int>(indices.size())));
    std::vector<std::thread> threads;
    for (int j = 1; j < jobs; ++j) threads.emplace_back(worker);
    worker();
    for (auto& t : threads) t.join();
    progress.Finish();
    part.close();
    if (!part) throw std::runtime_error(part_path + ": write failed");

    // Final file: rows sorted by (pair, method order), so output order does not depend on --jobs.
    std::vector<ResultRow> all = ReadPartialRows(part_path);
    std::map<std::string, std::size_t> order;
    for (std::size_t m = 0; m < options.methods.size(); ++m) order[options.methods[m].name] = m;
    std::stable_sort(all.begin(), all.end(), [&](const ResultRow& a, const ResultRow& b) {
        return std::make_pair(a.pair, order[a.method]) < std::make_pair(b.pair, order[b.method]);
    });
    WriteResultRows(options.out_path, all);
    std::filesystem::remove(part_path);
    summary.rows_written = written.load();
    summary.failures = failures.load();
    summary.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
}

}  // namespace regbench
