#include "core/output_rule.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <vector>

namespace regbench {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void Refuse(const std::string& out, const std::string& why) {
    throw std::runtime_error(out + ": " + why);
}

/// "dir/" and "dir" are the same output (lstat("link/") would follow the link).
std::string WithoutTrailingSlashes(std::string path) {
    while (path.size() > 1 && path.back() == '/') path.pop_back();
    return path;
}

/// The absolute path with every link resolved as far as it exists; empty when it cannot be.
fs::path Resolved(const std::string& path) {
    std::error_code ec;
    fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
    if (ec) return {};
    return p.lexically_normal();
}

/// `inner` is `outer` or lies inside it (component by component: "/a/bc" is not inside "/a/b").
bool EqualOrInside(const fs::path& inner, const fs::path& outer) {
    if (inner.empty() || outer.empty()) return false;
    auto skip_empty_tail = [](const fs::path& p) {
        auto end = p.end();
        if (p.begin() != end && std::prev(end)->empty()) --end;
        return end;
    };
    const auto outer_end = skip_empty_tail(outer);
    const auto inner_end = skip_empty_tail(inner);
    const auto [o, i] = std::mismatch(outer.begin(), outer_end, inner.begin(), inner_end);
    (void)i;
    return o == outer_end;
}

/// The kind of thing at `out` (never a link), then whether it may be replaced.
void CheckExisting(const std::string& out, const struct stat& st, const OutputRule& rule) {
    if (rule.folder && !S_ISDIR(st.st_mode)) {
        Refuse(out, "output folder exists and is not a folder");
    }
    if (!rule.folder && S_ISDIR(st.st_mode)) Refuse(out, "output is a directory");
    if (!rule.folder && !S_ISREG(st.st_mode)) {
        Refuse(out, "output exists and is not a regular file (refusing to replace it)");
    }
    if (!rule.replace && !rule.continues) {
        // A run's OUT.part (or OUT) that another regbench is writing right now: name the
        // writer, since --force would be refused by its lock anyway.
        const std::string holder = OutputLockHolder(out);
        if (!holder.empty()) {
            Refuse(out, "is being written by another regbench process (pid " + holder +
                            "); wait for it to finish");
        }
        Refuse(out, "already exists; " + rule.how_to_replace);
    }
}

/// Equal to an input first (by inode, so hard links count, or by resolved path), then inside
/// one, then (a folder to be replaced) holding one: the most direct reason is the one named.
void CheckInputs(const std::string& out, bool exists, const struct stat& st,
                 const std::vector<std::string>& inputs, const OutputRule& rule) {
    const fs::path out_path = Resolved(out);
    std::vector<std::pair<std::string, fs::path>> present;
    for (const auto& in : inputs) {
        struct stat ist {};
        if (in.empty() || ::stat(in.c_str(), &ist) != 0) continue;
        const fs::path in_path = Resolved(in);
        if ((exists && ist.st_dev == st.st_dev && ist.st_ino == st.st_ino) ||
            (!out_path.empty() && out_path == in_path)) {
            Refuse(out, "output is the same file as the input " + in);
        }
        present.emplace_back(in, in_path);
    }
    for (const auto& [in, in_path] : present) {
        if (EqualOrInside(out_path, in_path)) Refuse(out, "output lies inside the input " + in);
    }
    if (!rule.folder || rule.continues) return;
    for (const auto& [in, in_path] : present) {
        if (EqualOrInside(in_path, out_path)) {
            Refuse(out, "output folder holds the input " + in +
                            "; replacing the folder would destroy it");
        }
    }
}

/// A folder output must be a folder of its own: "." or ".." put its lock, its temporaries and
/// (import-checkpoint --force) its replacement on the folder the user stands in or the one above
/// it, and so does any path that resolves to the current folder or one holding it.
void CheckFolderName(const std::string& out_arg, const std::string& out) {
    const std::string last = fs::path(out).filename().string();
    if (last == "." || last == "..") {
        throw OutputPathError(out_arg + ": an output folder must be named by its own name, not '" +
                              last + "' (give e.g. ../run or ./run)");
    }
    std::error_code ec;
    const fs::path cwd = fs::current_path(ec);
    const fs::path out_path = Resolved(out);
    if (!ec && EqualOrInside(cwd.lexically_normal(), out_path)) {
        throw OutputPathError(out_arg + ": output folder " + out_path.string() +
                              (out_path == cwd.lexically_normal()
                                   ? " is the current folder"
                                   : " holds the current folder") +
                              "; give a folder of its own (e.g. ./run)");
    }
}

}  // namespace

void CheckOutputRule(const std::string& out_arg, const std::vector<std::string>& inputs,
                     const OutputRule& rule) {
    if (out_arg.empty()) throw std::invalid_argument("output path is empty");
    const std::string out = WithoutTrailingSlashes(out_arg);
    if (out.size() >= 5 && out.compare(out.size() - 5, 5, ".lock") == 0) {
        Refuse(out_arg,
               "output names a lock file (regbench keeps OUT.lock beside every output it "
               "writes); pick another name");
    }
    if (rule.folder) CheckFolderName(out_arg, out);
    struct stat st {};
    const bool exists = ::lstat(out.c_str(), &st) == 0;
    if (exists && S_ISLNK(st.st_mode)) {
        Refuse(out_arg,
               "output is a symbolic link; refusing to write through it (give the real path)");
    }
    CheckInputs(out_arg, exists, st, inputs, rule);
    if (exists) CheckExisting(out_arg, st, rule);
    if (!rule.folder) {
        const fs::path parent = fs::path(out).parent_path();
        const std::string dir = parent.empty() ? std::string(".") : parent.string();
        struct stat dst {};
        if (::stat(dir.c_str(), &dst) != 0 || !S_ISDIR(dst.st_mode)) {
            Refuse(out_arg, "directory " + dir + " does not exist");
        }
    }
}

const std::string& ClaimedOutput::Checked(const std::string& out,
                                          const std::vector<std::string>& inputs,
                                          const OutputRule& rule) {
    CheckOutputRule(out, inputs, rule);
    if (rule.folder) CreateParentFolders(out);
    return out;
}

ClaimedOutput::ClaimedOutput(const std::string& out, const std::vector<std::string>& inputs,
                             const OutputRule& rule)
    : lock_(Checked(out, inputs, rule)) {
    CheckOutputRule(out, inputs, rule);  // again, now that no other regbench writes it
}

}  // namespace regbench
