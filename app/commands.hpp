#pragma once
// Each regbench subcommand lives in its own app/cmd_*.cpp and registers itself there with one
// RegisterCommand line (name, one-line summary, setup function); main.cpp adds the registered
// commands to the CLI in its help order. A new subcommand is therefore one new file.
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace regbench::app {

struct Command {
    const char* name;     ///< the subcommand's word, e.g. "run"
    const char* summary;  ///< one line for `regbench --help`
    /// Adds the options and the callback to the subcommand (already named and summarised).
    void (*setup)(CLI::App* cmd);
};

/// Records a subcommand; called while static objects are initialised, so that a command file
/// needs no line anywhere else. Returns true for a namespace-scope constant to hold.
bool RegisterCommand(const Command& command);

/// `text` on one line: newlines and runs of spaces become single spaces, trailing space dropped
/// (usage errors are printed as one line).
inline std::string OneLine(const std::string& text) {
    std::string out;
    for (const char c : text) {
        const bool space = c == '\n' || c == '\r' || c == '\t' || c == ' ';
        if (space) {
            if (!out.empty() && out.back() != ' ') out += ' ';
        } else {
            out += c;
        }
    }
    while (!out.empty() && out.back() == ' ') out.pop_back();
    return out;
}

/// Every registered subcommand (registration order across files is unspecified).
const std::vector<Command>& RegisteredCommands();

}  // namespace regbench::app
