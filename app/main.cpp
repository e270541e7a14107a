// regbench: benchmark and evaluation harness for rigid point-cloud registration.
#include <unistd.h>

#include <cstdlib>
#include <exception>
#include <iostream>
#include <string>

#include "app/commands.hpp"
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

}  // namespace

int main(int argc, char** argv) {
    EnsurePassiveOmpWaitPolicy(argv);
    CLI::App app{"regbench: reproducible benchmarks for rigid point-cloud registration"};
    app.set_version_flag("--version", std::string("regbench ") + regbench::RegbenchVersion() +
                                          " (git " + regbench::RegbenchGitSha() + ")");
    app.require_subcommand(1);
    regbench::app::AddMethodsCommand(app);
    regbench::app::AddRunCommand(app);
    regbench::app::AddReportCommand(app);
    regbench::app::AddScoreCommand(app);
    regbench::app::AddAlignCommand(app);
    regbench::app::AddGenerateCommand(app);
    regbench::app::AddInspectCommand(app);
    regbench::app::AddExportCommand(app);
    regbench::app::AddImportCommand(app);
    regbench::app::AddCompareCommand(app);
    regbench::app::AddReproduceCommand(app);
    regbench::app::AddTrainCommand(app);
    regbench::app::AddMergeCommand(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    } catch (const std::exception& e) {
        std::cerr << "regbench: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
