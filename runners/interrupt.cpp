#include "runners/interrupt.hpp"

#include <signal.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <cstring>
#include <stdexcept>

namespace regbench {
namespace {

// Signal handlers can reach only globals. Filled before the handlers are installed, read-only
// afterwards; the text is preformatted because a handler may not allocate.
const std::atomic<std::size_t>* g_rows_safe = nullptr;
char g_part_path[4096];
char g_resume_command[8192];
struct sigaction g_old_int;
struct sigaction g_old_term;
bool g_installed = false;

void WriteStr(const char* s) {
    std::size_t n = std::strlen(s);
    while (n > 0) {
        const ssize_t w = ::write(STDERR_FILENO, s, n);
        if (w <= 0) return;
        s += w;
        n -= static_cast<std::size_t>(w);
    }
}

/// Async-signal-safe decimal formatting.
void WriteNumber(std::size_t v) {
    char buf[32];
    int i = sizeof(buf) - 1;
    buf[i] = '\0';
    do {
        buf[--i] = static_cast<char>('0' + v % 10);
        v /= 10;
    } while (v > 0 && i > 0);
    WriteStr(buf + i);
}

void OnInterrupt(int sig) {
    WriteStr("\nregbench: interrupted by signal ");
    WriteNumber(static_cast<std::size_t>(sig));
    WriteStr(": ");
    WriteNumber(g_rows_safe != nullptr ? g_rows_safe->load() : 0);
    WriteStr(" rows are safe in ");
    WriteStr(g_part_path);
    WriteStr("\nresume with: ");
    WriteStr(g_resume_command);
    WriteStr("\n");
    // Default action: the exit status says "killed by SIGINT/SIGTERM". Forked workers get
    // SIGKILL from PR_SET_PDEATHSIG.
    ::signal(sig, SIG_DFL);
    ::raise(sig);
}

void CopyBounded(char* dst, std::size_t cap, const std::string& src) {
    const std::size_t n = std::min(cap - 1, src.size());
    std::memcpy(dst, src.data(), n);
    dst[n] = '\0';
}

}  // namespace

InterruptNotice::InterruptNotice(const std::atomic<std::size_t>* rows_safe,
                                 const std::string& part_path, const std::string& resume_command) {
    if (g_installed) throw std::logic_error("InterruptNotice: one at a time");
    g_rows_safe = rows_safe;
    CopyBounded(g_part_path, sizeof(g_part_path), part_path);
    CopyBounded(g_resume_command, sizeof(g_resume_command), resume_command);
    struct sigaction sa {};
    sa.sa_handler = OnInterrupt;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND;
    sigaction(SIGINT, &sa, &g_old_int);
    sigaction(SIGTERM, &sa, &g_old_term);
    g_installed = true;
}

InterruptNotice::~InterruptNotice() {
    sigaction(SIGINT, &g_old_int, nullptr);
    sigaction(SIGTERM, &g_old_term, nullptr);
    g_rows_safe = nullptr;
    g_installed = false;
}

void BecomeDisposableChild(int parent) {
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(1);  // the parent died before prctl took effect
}

}  // namespace regbench
