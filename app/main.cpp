// regbench: benchmark and evaluation harness for rigid point-cloud registration.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "app/commands.hpp"
#include "core/memory_policy.hpp"
#include "core/output_rule.hpp"
#include "core/usage_error.hpp"
#include "core/version.hpp"

namespace {

/// Makes idle OpenMP threads sleep instead of spinning (OMP_WAIT_POLICY=PASSIVE) unless the
/// user chose a policy. libgomp spins up to ~300k iterations by default before sleeping; on a
/// shared or oversubscribed machine the spinning worker steals the core the working thread
/// needs, so `--threads 2` ran 15x slower than 1 thread. libgomp reads the variable once, when
/// the library loads (before main), so setting it here only takes effect after re-executing
/// the binary; the re-executed process finds the variable set and goes on. If exec fails, the
/// run continues with libgomp's default policy (slower under contention, same results).
void EnsurePassiveOmpWaitPolicy(char** argv) {
    if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
    setenv("OMP_WAIT_POLICY", "PASSIVE", /*overwrite=*/1);
    execv("/proc/self/exe", argv);
    std::cerr << "regbench: warning: could not re-execute with OMP_WAIT_POLICY=PASSIVE; "
                 "OpenMP threads will spin while idle\n";
}

/// `regbench --help` lists the subcommands in this order (most used first); a registered
/// command missing from the list comes after these, by name.
constexpr std::string_view kHelpOrder[] = {"methods",   "run",     "report", "score",  "align",
                                           "generate",  "inspect", "export", "import", "compare",
                                           "reproduce", "train",   "merge"};

void AddCommands(CLI::App& app) {
    std::vector<regbench::app::Command> commands = regbench::app::RegisteredCommands();
    const auto rank = [](const regbench::app::Command& c) {
        const auto* it = std::find(std::begin(kHelpOrder), std::end(kHelpOrder), c.name);
        return std::make_pair(it - std::begin(kHelpOrder), std::string_view(c.name));
    };
    std::sort(commands.begin(), commands.end(),
              [&](const auto& a, const auto& b) { return rank(a) < rank(b); });
    for (const auto& c : commands) c.setup(app.add_subcommand(c.name, c.summary));
}

/// The usage error for a first word that names no subcommand ("regbench frobnicate"), listing
/// the subcommands in help order; empty when argv's first word that is not an option (the top
/// level has --help and --version only) is a subcommand, or there is none. CLI11 would answer
/// "A subcommand is required", as if none had been given.
std::string UnknownSubcommand(CLI::App& app, int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
        const std::string word = argv[i];
        if (!word.empty() && word[0] == '-') continue;
        std::string known;
        for (const CLI::App* c : app.get_subcommands([](CLI::App*) { return true; })) {
            if (c->get_name() == word) return "";
            known += (known.empty() ? "" : ", ") + c->get_name();
        }
        return "unknown subcommand '" + word + "'; the subcommands are " + known;
    }
    return "";
}

}  // namespace

namespace regbench::app {
namespace {

/// A function-local static, so that registrations from other files' static initialisers
/// cannot run before the vector exists.
std::vector<Command>& CommandList() {
    static std::vector<Command> commands;
    return commands;
}

}  // namespace

bool RegisterCommand(const Command& command) {
    CommandList().push_back(command);
    return true;
}

const std::vector<Command>& RegisteredCommands() { return CommandList(); }

}  // namespace regbench::app

int main(int argc, char** argv) {
    // A file-size limit (ulimit -f) must end a write with EFBIG, which every writer checks and
    // reports naming the file (and removes its temporary), instead of killing the process
    // silently by SIGXFSZ. Ignored dispositions survive the exec below.
    ::signal(SIGXFSZ, SIG_IGN);
    EnsurePassiveOmpWaitPolicy(argv);
    // Network forwards and training steps free and reallocate the same large tensors on every
    // call: keep freed memory for reuse instead of page-faulting it in again each time.
    regbench::RetainFreedMemory();
    CLI::App app{"regbench: reproducible benchmarks for rigid point-cloud registration"};
    app.set_version_flag("--version", std::string("regbench ") + regbench::RegbenchVersion() +
                                          " (git " + regbench::RegbenchGitSha() + ")");
    app.require_subcommand(1);
    AddCommands(app);
    if (const std::string unknown = UnknownSubcommand(app, argc, argv); !unknown.empty()) {
        std::cerr << "regbench: usage error: " << unknown << " (see regbench --help)\n";
        return 2;
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // --help, --version and a command's own exit status (compare's 1 and 3) as CLI11
        // prints them; every other parse or validation error is a usage error: exit 2, one
        // plain line.
        const std::string name = e.get_name();
        if (e.get_exit_code() == 0 || name == "RuntimeError" || name == "CallForHelp" ||
            name == "CallForAllHelp" || name == "CallForVersion") {
            return app.exit(e);
        }
        // CLI11 names a hidden option (run's --method) as "", leaving ": " before its message.
        std::string what = e.what();
        if (what.rfind(": ", 0) == 0) what.erase(0, 2);
        std::cerr << "regbench: usage error: " << regbench::app::OneLine(what)
                  << " (see regbench --help)\n";
        return 2;
    } catch (const regbench::UsageError& e) {
        // Found below app/ (core/usage_error.hpp): an output path that names no folder of its
        // own (".", "..", the current folder), an unknown `reproduce --tables` name. The command
        // line is at fault, as with a refused flag value.
        std::cerr << "regbench: usage error: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "regbench: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
