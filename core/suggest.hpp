#pragma once
// "did you mean" for a mistyped name (a method, a protocol, an option): the known name closest
// to the given one by edit distance, when it is close enough to be the likely intent.
#include <algorithm>
#include <cctype>
#include <cstddef>
#include <string>
#include <vector>

namespace regbench {

/// Levenshtein distance (insert, delete, substitute one character), case-insensitive.
inline std::size_t EditDistance(const std::string& a, const std::string& b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                              std::tolower(static_cast<unsigned char>(b[j - 1]));
            const std::size_t next = std::min({row[j] + 1, row[j - 1] + 1, diagonal + !same});
            diagonal = row[j];
            row[j] = next;
        }
    }
    return row[b.size()];
}

/// The known name nearest to `name` when at most max(2, |name| / 3) edits away (the first of
/// equally near ones), or one that starts with `name` (an abbreviation); empty otherwise.
inline std::string ClosestName(const std::string& name, const std::vector<std::string>& known) {
    std::string best;
    std::size_t best_distance = std::max<std::size_t>(2, name.size() / 3) + 1;
    for (const auto& k : known) {
        const std::size_t d = EditDistance(name, k);
        if (d < best_distance) {
            best = k;
            best_distance = d;
        }
    }
    if (best.empty() && name.size() >= 2) {
        for (const auto& k : known) {
            if (k.compare(0, name.size(), name) == 0) return k;
        }
    }
    return best;
}

/// "did you mean 'x'? " when a known name is close to `name`, else "".
inline std::string DidYouMean(const std::string& name, const std::vector<std::string>& known) {
    const std::string best = ClosestName(name, known);
    return best.empty() ? std::string() : "did you mean '" + best + "'? ";
}

}  // namespace regbench
