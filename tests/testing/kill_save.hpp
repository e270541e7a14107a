#pragma once
// A checkpoint save killed at one of its steps: the child process the kill-at-every-step tests
// fork (networks/checkpoint/checkpoint.cpp, REGBENCH_TEST_KILL_SAVE_AT). POSIX and the standard
// library only, so every test folder can use it.
#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <functional>
#include <string>

namespace regbench::testing {

/// Runs `save` in a forked child with REGBENCH_TEST_KILL_SAVE_AT=`step`, so the checkpoint
/// writer kills its own process (SIGKILL) right after that step of a save. Returns the child's
/// wait status (-1 when it could not be forked or waited for); the child exits 0 when `save`
/// returned, 3 when it threw.
inline int RunSaveKilledAtStep(int step, const std::function<void()>& save) {
    const pid_t pid = fork();
    if (pid == 0) {
        setenv("REGBENCH_TEST_KILL_SAVE_AT", std::to_string(step).c_str(), 1);
        try {
            save();
        } catch (...) {
            _exit(3);
        }
        _exit(0);
    }
    int status = 0;
    if (pid < 0 || waitpid(pid, &status, 0) != pid) return -1;
    return status;
}

/// "" when wait status `status` is a kill by SIGKILL, else what it is instead.
inline std::string NotKilledBySigkill(int status) {
    if (status == -1) return "no child process";
    if (!WIFSIGNALED(status)) return "exited " + std::to_string(WEXITSTATUS(status));
    if (WTERMSIG(status) != SIGKILL) return "signal " + std::to_string(WTERMSIG(status));
    return "";
}

}  // namespace regbench::testing
