#include "networks/checkpoint/checkpoint_json.hpp"

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "core/json_limits.hpp"

namespace regbench::networks {
namespace {
constexpr char kFormat[] = "regbench-checkpoint";

std::string Dump(const nlohmann::json& v) {
    return v.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}
/// The one checkpoint format this regbench writes; SaveCheckpoint's weights file name.
constexpr int kFormatVersion = 1;
constexpr char kWeightsName[] = "weights.pt";
constexpr double kMaxWeightsBytes = 9007199254740992.0;  // 2^53

void CheckFormatAndWeights(const nlohmann::json& j, const std::string& where) {
    if (j.contains("format_version")) {
        const nlohmann::json& v = j.at("format_version");
        if (!v.is_number_integer() || v.get<std::int64_t>() != kFormatVersion) {
            throw std::runtime_error(where + ": format_version " + Dump(v) +
                                     " is not supported (this regbench reads version " +
                                     std::to_string(kFormatVersion) + ")");
        }
    }
    if (j.contains("weights")) {
        const nlohmann::json& w = j.at("weights");
        if (!w.is_string()) {
            throw std::runtime_error(where + ": 'weights' must be a file name, got " + Dump(w));
        }
        const std::string name = w.get<std::string>();
        std::string why;
        if (!name.empty() && name[0] == '/') {
            why = "is an absolute path";
        } else if (name == ".." || name.rfind("../", 0) == 0 ||
                   name.find("/../") != std::string::npos ||
                   (name.size() >= 3 && name.compare(name.size() - 3, 3, "/..") == 0)) {
            why = "leaves the checkpoint folder ('..')";
        } else if (name != kWeightsName) {
            why = std::string("is not the weights file this regbench reads (") + kWeightsName +
                  " in the checkpoint folder)";
        }
        if (!why.empty()) {
            throw std::runtime_error(where + ": 'weights' " + Dump(w) + " " + why);
        }
    }
    if (j.contains("weights_bytes")) {
        const nlohmann::json& b = j.at("weights_bytes");
        if (!b.is_number_unsigned() || b.get<std::uint64_t>() < 1 ||
            static_cast<double>(b.get<std::uint64_t>()) > kMaxWeightsBytes) {
            throw std::runtime_error(where + ": 'weights_bytes' must be a whole number >= 1, got " +
                                     Dump(b));
        }
    }
}

std::uint32_t Le32(std::string_view s, std::size_t at) {
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i) {
        v = (v << 8) | static_cast<unsigned char>(s[at + static_cast<std::size_t>(i)]);
    }
    return v;
}

}  // namespace

void CheckWeightsBytes(std::string_view head, std::string_view tail, std::uint64_t size,
                       const nlohmann::json& checkpoint, const std::string& path) {
    const auto fail = [&](const std::string& why) {
        throw std::runtime_error("weights file " + path + " " + why);
    };
    if (size == 0) fail("is empty");
    if (checkpoint.contains("weights_bytes") &&
        checkpoint.at("weights_bytes").is_number_unsigned() &&
        checkpoint.at("weights_bytes").get<std::uint64_t>() != size) {
        fail("has " + std::to_string(size) + " bytes but checkpoint.json records " +
             Dump(checkpoint.at("weights_bytes")) + " (truncated or replaced)");
    }
    if (head.size() < 4 || head.substr(0, 4) != std::string_view("PK\x03\x04", 4)) {
        fail("is not a torch weights archive (no zip header; garbage or another format)");
    }
    // The end-of-central-directory record, searched from the end (a comment may follow it).
    constexpr std::string_view kEnd("PK\x05\x06", 4);
    if (tail.size() > size) fail("is shorter than the bytes read from it (changed while read)");
    for (std::size_t i = tail.size() >= 22 ? tail.size() - 22 + 1 : 0; i-- > 0;) {
        if (tail.substr(i, 4) != kEnd) continue;
        const std::uint64_t record_at = size - (tail.size() - i);
        const std::uint32_t cd_size = Le32(tail, i + 12);
        const std::uint32_t cd_offset = Le32(tail, i + 16);
        // 0xFFFFFFFF: a zip64 archive keeps the real numbers elsewhere.
        if (cd_offset != 0xFFFFFFFFu && cd_size != 0xFFFFFFFFu &&
            static_cast<std::uint64_t>(cd_offset) + cd_size > record_at) {
            fail("is truncated or damaged (its zip directory points past the end)");
        }
        return;
    }
    fail("is truncated (no end of zip archive)");
}

void CheckTrainerStateJson(const nlohmann::json& j) {
    if (!j.is_object()) throw std::invalid_argument("trainer state is not an object");
    if (!j.contains("step") || j.at("step").is_null()) {
        throw std::invalid_argument("trainer state: no 'step'");
    }
    const auto bad = [&](const std::string& key, const std::string& need) {
        throw std::invalid_argument("trainer state: '" + key + "' is " + Dump(j.at(key)) +
                                    ", expected " + need);
    };
    const auto given = [&](const char* key) { return j.contains(key) && !j.at(key).is_null(); };
    for (const char* key :
         {"step", "planned_steps", "pairs_seen", "plateau_bad", "epoch_loss_steps"}) {
        if (!given(key)) continue;
        const nlohmann::json& v = j.at(key);
        if (!v.is_number_integer() ||
            (v.is_number_unsigned() ? v.get<std::uint64_t>() > (1ULL << 53)
                                    : v.get<std::int64_t>() < 0)) {
            bad(key, "a whole number in [0, 2^53]");
        }
    }
    if (given("plateau_bad") && j.at("plateau_bad").get<std::int64_t>() > 1000000000) {
        bad("plateau_bad", "a whole number in [0, 1e9]");
    }
    for (const char* key : {"lr", "elapsed_seconds", "cpu_seconds", "plateau_scale"}) {
        if (!given(key)) continue;
        const nlohmann::json& v = j.at(key);
        if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() < 0) {
            bad(key, "a finite number >= 0");
        }
    }
    for (const char* key : {"best_mae_r", "plateau_best", "epoch_loss_sum"}) {
        if (given(key) && (!j.at(key).is_number() || !std::isfinite(j.at(key).get<double>()))) {
            bad(key, "a finite number (or null)");
        }
    }
}

nlohmann::json ParseCheckpointJson(const std::string& text, const std::string& path) {
    const std::string where = "checkpoint file " + path;
    nlohmann::json j;
    try {
        j = ParseJsonBounded(text, where);
    } catch (const std::exception& e) {
        throw std::runtime_error(where + " is not valid JSON: " + e.what());
    }
    if (!j.is_object() || !j.contains("format") || !j.at("format").is_string() ||
        j.at("format").get<std::string>() != kFormat || !j.contains("model_config")) {
        throw std::runtime_error(where + " is not a regbench checkpoint (no format/model_config)");
    }
    if (!j.at("model_config").is_object()) {
        throw std::runtime_error(where + ": 'model_config' must be an object, got " +
                                 Dump(j.at("model_config")));
    }
    if (j.contains("config")) {
        const nlohmann::json& c = j.at("config");
        if (!c.is_object()) {
            throw std::runtime_error(where + ": 'config' must be an object, got " + Dump(c));
        }
        if (c.contains("arch") && !c.at("arch").is_string()) {
            throw std::runtime_error(where + ": 'config.arch' must be a string, got " +
                                     Dump(c.at("arch")));
        }
    }
    CheckFormatAndWeights(j, where);
    if (j.contains("trainer")) {
        try {
            CheckTrainerStateJson(j.at("trainer"));
        } catch (const std::exception& e) {
            throw std::runtime_error(where + ": " + e.what());
        }
    }
    return j;
}

std::string CheckpointArch(const nlohmann::json& checkpoint) {
    if (!checkpoint.contains("config")) return "";
    return checkpoint.at("config").value("arch", std::string());
}

}  // namespace regbench::networks
