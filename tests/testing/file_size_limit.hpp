#pragma once
// A write under a size-limited disk: the child process the tests of checked writes fork.
// POSIX and the standard library only, so every test folder can use it.
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <exception>
#include <functional>
#include <string>

namespace regbench::testing {

/// Runs `write` in a forked child under RLIMIT_FSIZE = `limit` bytes with SIGXFSZ ignored (so a
/// write past the limit fails with EFBIG instead of killing the process, as on a full disk).
/// Returns the child's wait status; the child exits 3 when `write` threw an E naming
/// `expect_in_message`, 4 when it threw an E not naming it, 0 when it did not throw (any other
/// exception ends the child by a signal).
template <typename E = std::exception>
int RunUnderFileSizeLimit(rlim_t limit, const std::string& expect_in_message,
                          const std::function<void()>& write) {
    const pid_t pid = fork();
    if (pid == 0) {
        signal(SIGXFSZ, SIG_IGN);
        rlimit rl{limit, limit};
        setrlimit(RLIMIT_FSIZE, &rl);
        try {
            write();
        } catch (const E& e) {
            _exit(std::strstr(e.what(), expect_in_message.c_str()) != nullptr ? 3 : 4);
        }
        _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    return status;
}

}  // namespace regbench::testing
