#pragma once
// "did you mean" for a mistyped name (a method, a protocol, an option): the known name closest
// to the given one by edit distance, when it is close enough to be the likely intent.
#include <algorithm>
#include <cctype>
#include <cstddef>
#include <string>
#include <vector>

namespace regbench {

/// Edit distance with transpositions (optimal string alignment: insert, delete, substitute or
/// swap two adjacent characters, each one edit), case-insensitive: "cdp" is one edit from "cpd".
inline std::size_t EditDistance(const std::string& a, const std::string& b) {
    const auto same = [&](std::size_t i, std::size_t j) {  // a[i - 1] == b[j - 1]
        return std::tolower(static_cast<unsigned char>(a[i - 1])) ==
               std::tolower(static_cast<unsigned char>(b[j - 1]));
    };
    const std::size_t w = b.size() + 1;
    std::vector<std::size_t> d((a.size() + 1) * w);
    for (std::size_t i = 0; i <= a.size(); ++i) d[i * w] = i;
    for (std::size_t j = 0; j <= b.size(); ++j) d[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        for (std::size_t j = 1; j <= b.size(); ++j) {
            std::size_t v = std::min({d[(i - 1) * w + j] + 1, d[i * w + j - 1] + 1,
                                      d[(i - 1) * w + j - 1] + !same(i, j)});
            if (i > 1 && j > 1 && same(i, j - 1) && same(i - 1, j))
                v = std::min(v, d[(i - 2) * w + j - 2] + 1);
            d[i * w + j] = v;
        }
    }
    return d.back();
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
