#include "runners/isolated_call.hpp"

#include <omp.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <string>

#include "runners/interrupt.hpp"

namespace regbench {
namespace {

CallOutcome Failure(Status status, const std::string& message, double seconds) {
    CallOutcome out;
    out.result.status = AlignStatus::kFailed;
    out.result.message = message;
    out.result.stop_reason = ToString(status);
    out.result.seconds = seconds;
    out.status = status;
    return out;
}

/// The forked child: runs the call, writes its AlignResult as JSON to fds[1] and ends in
/// _exit.
[[noreturn]] void RunChild(RegistrationMethod& method, const Pair& pair,
                           const AlignContext& context, int threads, const ForkHooks& hooks,
                           pid_t parent, const int fds[2]) {
    // The child owns nothing of the parent's: it must never unwind into the parent's
    // frames (whose destructors would remove the parent's output lock or temporaries) nor
    // run exit()'s atexit handlers. Everything it does ends in _exit, and an exception is
    // turned into a `failed` result with the reason.
    int code = 0;
    try {
        BecomeDisposableChild(parent);  // dies with the parent: no orphan keeps computing
        if (hooks.child) hooks.child();
        close(fds[0]);
        omp_set_num_threads(threads);
        std::string payload;
        try {
            // A message holding a library's non-UTF-8 bytes is sent with U+FFFD for them
            // instead of throwing type_error.316 here.
            payload = nlohmann::json(method.Align(pair.source, pair.target, context))
                          .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
        } catch (const std::exception& e) {
            AlignResult failed;
            failed.status = AlignStatus::kFailed;
            failed.stop_reason = "exception";
            failed.message = method.Name() + ": " + e.what();
            payload = nlohmann::json(failed).dump(-1, ' ', false,
                                                  nlohmann::json::error_handler_t::replace);
        }
        size_t off = 0;
        while (off < payload.size()) {
            const ssize_t n = write(fds[1], payload.data() + off, payload.size() - off);
            if (n <= 0) break;
            off += static_cast<size_t>(n);
        }
        close(fds[1]);
    } catch (...) {
        code = 70;  // no result: the parent records `crashed`
    }
    _exit(code);
}

/// Appends what `fd` delivers to `payload` until EOF (true) or until `timeout` seconds after
/// `start` (false).
bool ReadUntilEof(int fd, double timeout, std::chrono::steady_clock::time_point start,
                  std::string& payload) {
    char buf[65536];
    for (;;) {
        const double left =
            timeout -
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (left <= 0.0) return false;
        pollfd pfd{fd, POLLIN, 0};
        const int ready = poll(&pfd, 1, static_cast<int>(std::min(left, 1.0) * 1000.0) + 1);
        if (ready < 0 && errno != EINTR) return true;
        if (ready <= 0) continue;
        const ssize_t n = read(fd, buf, sizeof(buf));
        if (n <= 0) return true;  // EOF: child finished (or died)
        payload.append(buf, static_cast<size_t>(n));
    }
}

}  // namespace

Status StatusOf(const AlignResult& r) {
    return r.status == AlignStatus::kOk ? Status::kOk : Status::kFailed;
}

CallOutcome AlignIsolated(RegistrationMethod& method, const Pair& pair, const AlignContext& context,
                          double timeout, int threads, const ForkHooks& hooks) {
    int fds[2];
    if (pipe(fds) != 0)
        return Failure(Status::kFailed, "pipe() failed: " + std::string(strerror(errno)), 0);
    const pid_t parent = getpid();
    if (hooks.prepare) hooks.prepare();
    const pid_t pid = fork();
    if (pid != 0 && hooks.parent) hooks.parent();
    if (pid < 0) {
        close(fds[0]);
        close(fds[1]);
        return Failure(Status::kFailed, "fork() failed: " + std::string(strerror(errno)), 0);
    }
    if (pid == 0) RunChild(method, pair, context, threads, hooks, parent, fds);
    close(fds[1]);
    const auto start = std::chrono::steady_clock::now();
    std::string payload;
    const bool timed_out = !ReadUntilEof(fds[0], timeout, start, payload);
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
        out.result = nlohmann::json::parse(payload).get<AlignResult>();
        out.status = StatusOf(out.result);
        return out;
    } catch (const std::exception& e) {
        return Failure(Status::kCrashed, method.Name() + ": child exited without a result",
                       elapsed);
    }
}

CallOutcome AlignInProcess(RegistrationMethod& method, const Pair& pair,
                           const AlignContext& context) {
    CallOutcome out;
    out.result = method.Align(pair.source, pair.target, context);
    out.status = StatusOf(out.result);
    return out;
}

}  // namespace regbench
