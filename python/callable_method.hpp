#pragma once
// A Python callable as a RegistrationMethod, so the runner times, isolates, resumes and writes
// it like a registered method (RunOptions::external_methods).
#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/registration.hpp"
#include "runners/isolated_call.hpp"

namespace regbench::python {

namespace py = pybind11;

/// A BaseException that is not an Exception (KeyboardInterrupt, SystemExit) raised inside a
/// callable: it must end the run, not become a `failed` row. The callable stores it here and
/// the runner's check_interrupt hook rethrows it after the call.
///
/// With `timeout=` the callable runs in a forked child, whose memory the parent never sees: a
/// child stores what it caught in a shared anonymous mapping made before any fork, and the
/// parent raises it as KeyboardInterrupt.
class PendingInterrupt {
public:
    PendingInterrupt();  ///< throws std::runtime_error when the shared mapping cannot be made
    ~PendingInterrupt();
    PendingInterrupt(const PendingInterrupt&) = delete;
    PendingInterrupt& operator=(const PendingInterrupt&) = delete;

    /// Called with the interpreter lock held, in the run's process or in a forked child.
    void Store(const py::error_already_set& e);
    /// Throws the stored exception, if any (any thread; takes the lock only to raise one that
    /// a child stored).
    void RethrowIfAny();

private:
    struct Shared;
    const long owner_pid_;  ///< the run's process: Store in any other is a forked child's
    Shared* shared_;        ///< MAP_SHARED: written by a child, read by the run's process
    std::mutex mutex_;
    std::optional<py::error_already_set> error_;
};

/// Calls fn(source, target, **params) with the interpreter lock held, only for the call. The
/// clouds are fresh float64 (N, 3) arrays. fn returns a 4x4 array-like, or a dict with
/// "transform" plus optional "iterations" (int), "stop_reason" (str) and any other keys, which
/// go to the row's `extra`. An Exception becomes a failed call whose message is
/// "<name>: <ExceptionType>: <text>". Time spent waiting for the interpreter lock is reported
/// as extra.excluded_seconds, which Align takes off `seconds`.
///
/// Holds `fn` as a borrowed handle: the caller keeps it alive for the instance's life (run()
/// holds its arguments), so instances can be made and destroyed on threads without the lock.
class CallableMethod final : public RegistrationMethod {
public:
    CallableMethod(std::string name, nlohmann::json params, py::handle fn,
                   std::shared_ptr<PendingInterrupt> pending)
        : name_(std::move(name)),
          params_(std::move(params)),
          fn_(fn),
          pending_(std::move(pending)) {}
    std::string Name() const override { return name_; }
    nlohmann::json Params() const override { return params_; }

protected:
    AlignResult DoAlign(const PointCloud& source, const PointCloud& target,
                        const AlignContext& context) override;

private:
    std::string name_;
    nlohmann::json params_;
    py::handle fn_;
    std::shared_ptr<PendingInterrupt> pending_;
};

/// Hooks that hand the interpreter to the child of an isolated call: the forking thread takes
/// the lock and runs CPython's fork protocol (PyOS_BeforeFork / AfterFork_Parent /
/// AfterFork_Child), so the child, whose only thread is the forking one, owns a consistent
/// interpreter and can call the callable.
ForkHooks InterpreterForkHooks();

/// "<ExceptionType>: <message>" of a Python exception (needs the lock).
std::string DescribePythonError(const py::error_already_set& e);

}  // namespace regbench::python
