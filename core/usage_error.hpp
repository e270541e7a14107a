#pragma once
// A refusal of the command line rather than of what is on disk, thrown below app/ (where
// CLI::ValidationError is out of reach): the CLI reports it as a usage error, exit 2.
#include <stdexcept>

namespace regbench {

/// A flag value or path the command line got wrong (an unknown table of `reproduce --tables`,
/// an output path that names no folder of its own). app/main.cpp prints it as
/// "regbench: usage error: ..." and exits 2; anything else thrown while working exits 1.
class UsageError : public std::invalid_argument {
public:
    using std::invalid_argument::invalid_argument;
};

}  // namespace regbench
