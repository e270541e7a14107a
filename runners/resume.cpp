#include "runners/resume.hpp"

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <set>
#include <stdexcept>
#include <utility>

namespace regbench {
namespace {

[[noreturn]] void Refuse(const std::string& where, const std::string& what) {
    throw std::runtime_error(where + ": " + what);
}

bool IsMatrix4(const nlohmann::json& t) {
    if (!t.is_array() || t.size() != 4) return false;
    for (const auto& row : t) {
        if (!row.is_array() || row.size() != 4) return false;
        for (const auto& v : row) {
            if (!v.is_number() && !v.is_null()) return false;
        }
    }
    return true;
}

/// Field name -> a check of its JSON type; the fields every result row carries.
void CheckRequiredFields(const nlohmann::json& row, const std::string& where) {
    using Check = bool (*)(const nlohmann::json&);
    static const std::pair<const char*, Check> kFields[] = {
        {"pair", [](const nlohmann::json& j) { return j.is_number_unsigned(); }},
        {"method", [](const nlohmann::json& j) { return j.is_string(); }},
        {"params", [](const nlohmann::json& j) { return j.is_object(); }},
        {"transform", [](const nlohmann::json& j) { return IsMatrix4(j); }},
        {"seconds", [](const nlohmann::json& j) { return j.is_number(); }},
        {"iterations", [](const nlohmann::json& j) { return j.is_number_integer(); }},
        {"stop_reason", [](const nlohmann::json& j) { return j.is_string(); }},
        {"status", [](const nlohmann::json& j) { return j.is_string(); }},
        {"message", [](const nlohmann::json& j) { return j.is_string(); }},
        {"metrics", [](const nlohmann::json& j) { return j.is_object(); }},
        {"data", [](const nlohmann::json& j) { return j.is_object(); }},
    };
    if (!row.is_object()) Refuse(where, "not a JSON object");
    for (const auto& [name, check] : kFields) {
        if (!row.contains(name)) Refuse(where, std::string("missing field '") + name + "'");
        if (!check(row.at(name)))
            Refuse(where, std::string("field '") + name + "' has the wrong type");
    }
}

}  // namespace

std::string PairFileHash(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error(path + ": cannot open to hash");
    std::uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a 64 offset basis
    std::vector<char> buf(1 << 20);
    while (in) {
        in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
        const auto n = static_cast<std::size_t>(in.gcount());
        for (std::size_t i = 0; i < n; ++i) {
            h ^= static_cast<unsigned char>(buf[i]);
            h *= 0x100000001b3ULL;  // FNV 64 prime
        }
    }
    if (in.bad()) throw std::runtime_error(path + ": read error while hashing");
    char text[32];
    std::snprintf(text, sizeof(text), "fnv1a64:%016llx", static_cast<unsigned long long>(h));
    return text;
}

void CheckResultRow(const nlohmann::json& row,
                    const RowExpectation& expect,
                    const std::string& where) {
    CheckRequiredFields(row, where);
    const std::string status = row.at("status").get<std::string>();
    if (status != "ok" && status != "failed" && status != "timeout" && status != "crashed") {
        Refuse(where, "unknown status '" + status + "'");
    }
    const auto pair = row.at("pair").get<std::uint64_t>();
    if (pair >= expect.num_pairs) {
        Refuse(where, "pair " + std::to_string(pair) + " is not in the pair file (" +
                          std::to_string(expect.num_pairs) + " pairs)");
    }
    if (static_cast<int>(pair % static_cast<std::uint64_t>(expect.shard_count)) !=
        expect.shard_index) {
        Refuse(where, "pair " + std::to_string(pair) + " belongs to another shard");
    }
    const std::string method = row.at("method").get<std::string>();
    const MethodSpec* spec = nullptr;
    for (const auto& m : expect.methods) {
        if (m.name == method) spec = &m;
    }
    if (spec == nullptr) Refuse(where, "method '" + method + "' is not in --methods");
    if (row.at("params") != spec->params) {
        Refuse(where, "method '" + method + "' ran with other parameters " +
                          row.at("params").dump() + " (this run: " + spec->params.dump() + ")");
    }
    const auto& data = row.at("data");
    const std::string hash = data.value("pairs_hash", std::string());
    if (hash != expect.pairs_hash) {
        Refuse(where, "row comes from another pair file (pairs_hash '" + hash + "', this run '" +
                          expect.pairs_hash + "')");
    }
}

std::vector<nlohmann::json> ReadResumableRows(const std::string& path,
                                              const RowExpectation& expect) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error(path + ": cannot open");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<nlohmann::json> rows;
    std::set<std::pair<std::uint64_t, std::string>> seen;
    std::size_t begin = 0;
    std::size_t line_no = 0;
    while (begin < text.size()) {
        ++line_no;
        const std::size_t end = text.find('\n', begin);
        const bool terminated = end != std::string::npos;
        const std::string line = text.substr(begin, terminated ? end - begin : std::string::npos);
        begin = terminated ? end + 1 : text.size();
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        const std::string where = path + ":" + std::to_string(line_no);
        nlohmann::json row;
        try {
            row = nlohmann::json::parse(line);
        } catch (const nlohmann::json::exception& e) {
            if (!terminated) break;  // the write a kill cut short: redone
            Refuse(where, std::string("not JSON: ") + e.what());
        }
        CheckResultRow(row, expect, where);
        const auto key = std::make_pair(row.at("pair").get<std::uint64_t>(),
                                        row.at("method").get<std::string>());
        if (!seen.insert(key).second) {
            Refuse(where, "duplicate row for pair " + std::to_string(key.first) + ", method '" +
                              key.second + "'");
        }
        rows.push_back(std::move(row));
    }
    return rows;
}

}  // namespace regbench
