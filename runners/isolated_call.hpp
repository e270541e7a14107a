#pragma once
// One method call of a run: in this process, or in a forked child so that a crash (a signal,
// an abort inside a library) or a hang becomes a `crashed` / `timeout` row instead of ending
// the whole run.
#include <functional>

#include "core/registration.hpp"
#include "protocols/pair.hpp"
#include "runners/result_row.hpp"

namespace regbench {

/// Result of one call plus the runner-level status (ok, failed, timeout, crashed).
struct CallOutcome {
    AlignResult result;
    Status status = Status::kOk;
};

/// kOk when the method returned a transform, kFailed when it reported a failure.
Status StatusOf(const AlignResult& r);

/// Called around the fork() of an isolated call, for a method that needs process state handed
/// to the child (the Python module's callables: the interpreter lock). Null members are skipped.
struct ForkHooks {
    std::function<void()> prepare;  ///< in the parent, right before fork()
    std::function<void()> parent;   ///< in the parent, right after fork() (also when it failed)
    std::function<void()> child;    ///< in the child, right after fork(), before Align
};

/// Calls method.Align on the pair in this process (a crash here ends the run).
CallOutcome AlignInProcess(RegistrationMethod& method, const Pair& pair,
                           const AlignContext& context);

/// Runs Align in a forked child with `threads` OpenMP threads. The child sends the result as
/// JSON through a pipe and dies with the parent (no orphan keeps computing). The parent kills
/// it after `timeout` seconds (status kTimeout); a child killed by a signal or exiting without
/// a result gives kCrashed. Failures carry the reason in result.message.
CallOutcome AlignIsolated(RegistrationMethod& method, const Pair& pair, const AlignContext& context,
                          double timeout, int threads, const ForkHooks& hooks = {});

}  // namespace regbench
