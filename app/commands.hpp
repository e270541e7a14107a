#pragma once
// Each regbench subcommand lives in its own app/cmd_*.cpp and registers itself here.
#include <CLI/CLI.hpp>

namespace regbench::app {

void AddMethodsCommand(CLI::App& app);
void AddRunCommand(CLI::App& app);
void AddReportCommand(CLI::App& app);
void AddGenerateCommand(CLI::App& app);
void AddInspectCommand(CLI::App& app);
void AddExportCommand(CLI::App& app);
void AddImportCommand(CLI::App& app);
void AddScoreCommand(CLI::App& app);
void AddAlignCommand(CLI::App& app);

}  // namespace regbench::app
