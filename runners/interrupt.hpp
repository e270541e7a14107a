#pragma once
// Ctrl-C and SIGTERM during a run: say how many rows are safe and how to resume, then die by
// the same signal (so shells and schedulers see the usual exit status).
#include <atomic>
#include <cstddef>
#include <string>

namespace regbench {

/// While alive, SIGINT and SIGTERM print
///   "regbench: interrupted by signal N: K rows are safe in PART" and "resume with: CMD"
/// to stderr and then re-raise the signal with its default action. `rows_safe` is read inside
/// the handler (lock-free atomic). Only one InterruptNotice may exist at a time; the previous
/// handlers are restored by the destructor.
class InterruptNotice {
public:
    InterruptNotice(const std::atomic<std::size_t>* rows_safe, const std::string& part_path,
                    const std::string& resume_command);
    ~InterruptNotice();
    InterruptNotice(const InterruptNotice&) = delete;
    InterruptNotice& operator=(const InterruptNotice&) = delete;
};

/// In a forked child: default SIGINT/SIGTERM actions (the parent reports, not the child) and
/// SIGKILL when the parent dies (PR_SET_PDEATHSIG), so a killed run leaves no orphan working.
/// `parent` is the parent's pid before fork(); if it already died, the child exits at once.
void BecomeDisposableChild(int parent);

}  // namespace regbench
