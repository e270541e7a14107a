#pragma once
// The one output rule every regbench writer follows (docs/usage.md, "Outputs"): checked before
// any work, and again once the output's lock is held.
#include <stdexcept>
#include <string>
#include <vector>

#include "core/file_lock.hpp"
#include "core/usage_error.hpp"

namespace regbench {

/// A refusal of the path itself, not of what is on disk: the command line is wrong (the CLI
/// reports it as a usage error, exit 2).
class OutputPathError : public UsageError {
public:
    using UsageError::UsageError;
};

/// How one command's output may meet what is already on disk.
struct OutputRule {
    /// --force (or --resume, where the command has it) was given: an existing output may be
    /// replaced or continued.
    bool replace = false;
    /// The output is a folder (reproduce, train, export, import-checkpoint), not one file.
    bool folder = false;
    /// A folder a second invocation continues by design (reproduce): an existing one is fine.
    /// (train refuses a folder holding a run itself unless --resume.)
    bool continues = false;
    /// The words that say how to replace it, in the refusal ("pass --force to replace it").
    std::string how_to_replace = "pass --force to replace it";
};

/// Refuses `out`, naming it, unless the rule allows it:
/// - an empty path, or a name ending in ".lock" (regbench's own lock files);
/// - a folder output named "." or ".." (or ending in "/." or "/.."), or resolving to the current
///   folder or a folder that holds it ("/", $HOME from inside it): OutputPathError;
/// - a symbolic link (file or folder): never written through;
/// - an existing output unless `rule.replace` or `rule.continues`; a file output that is a
///   folder or a special file, a folder output that is not a folder;
/// - an output equal to any of `inputs` or inside one of them (paths resolved, links
///   followed; a hard link to an input by inode); a folder output that would be replaced
///   (not `continues`) holding an input;
/// - a file output whose folder does not exist.
/// Inputs that are empty strings or do not exist are skipped. Throws std::runtime_error.
void CheckOutputRule(const std::string& out, const std::vector<std::string>& inputs,
                     const OutputRule& rule);

/// The rule and the lock together: checks, creates a folder output's missing parents, takes
/// OutputLock(out) and checks again under the lock (closes the race with a second writer).
class ClaimedOutput {
public:
    ClaimedOutput(const std::string& out, const std::vector<std::string>& inputs,
                  const OutputRule& rule);

private:
    static const std::string& Checked(const std::string& out,
                                      const std::vector<std::string>& inputs,
                                      const OutputRule& rule);
    OutputLock lock_;
};

}  // namespace regbench
