// regbench: benchmark and evaluation harness for rigid point-cloud registration.
#include <exception>
#include <iostream>
#include <string>

#include "app/commands.hpp"

int main(int argc, char** argv) {
    CLI::App app{"regbench: reproducible benchmarks for rigid point-cloud registration"};
    app.set_version_flag("--version", std::string("regbench ") + REGBENCH_VERSION + " (git " +
                                          REGBENCH_GIT_SHA + ")");
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
