#include "ogmm/checkpoint_json.hpp"

#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "core/json_limits.hpp"

namespace regbench::ogmm {
namespace {
constexpr char kFormat[] = "regbench-checkpoint";

std::string Dump(const nlohmann::json& v) {
    return v.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}
}  // namespace

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

}  // namespace regbench::ogmm
