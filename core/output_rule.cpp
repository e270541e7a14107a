#include "core/output_rule.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <system_error>

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

void CheckExisting(const std::string& out, const struct stat& st, const OutputRule& rule) {
    if (S_ISLNK(st.st_mode)) {
        Refuse(out, "output is a symbolic link; refusing to write through it (give the real path)");
    }
    if (rule.folder && !S_ISDIR(st.st_mode)) {
        Refuse(out, "output folder exists and is not a folder");
    }
    if (!rule.folder && S_ISDIR(st.st_mode)) Refuse(out, "output is a directory");
    if (!rule.folder && !S_ISREG(st.st_mode)) {
        Refuse(out, "output exists and is not a regular file (refusing to replace it)");
    }
    if (!rule.replace && !rule.continues) {
        Refuse(out, "output already exists; " + rule.how_to_replace);
    }
}

void CheckInputs(const std::string& out, bool exists, const struct stat& st,
                 const std::vector<std::string>& inputs, const OutputRule& rule) {
    const fs::path out_path = Resolved(out);
    for (const auto& in : inputs) {
        struct stat ist {};
        if (in.empty() || ::stat(in.c_str(), &ist) != 0) continue;
        if (exists && ist.st_dev == st.st_dev && ist.st_ino == st.st_ino) {
            Refuse(out, "output is the input " + in);
        }
        const fs::path in_path = Resolved(in);
        if (EqualOrInside(out_path, in_path)) {
            Refuse(out, out_path == in_path ? "output is the input " + in
                                            : "output lies inside the input " + in);
        }
        if (rule.folder && !rule.continues && EqualOrInside(in_path, out_path)) {
            Refuse(out, "output folder holds the input " + in +
                            "; replacing the folder would destroy it");
        }
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
    struct stat st {};
    const bool exists = ::lstat(out.c_str(), &st) == 0;
    if (exists) CheckExisting(out_arg, st, rule);
    CheckInputs(out_arg, exists, st, inputs, rule);
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
