#include "baselines/identity.hpp"

#include "core/options.hpp"

namespace regbench {
namespace {

struct IdentityOptions {};
void to_json(nlohmann::json& j, const IdentityOptions&) { j = nlohmann::json::object(); }
void from_json(const nlohmann::json&, IdentityOptions&) {}

class IdentityMethod final : public RegistrationMethod {
public:
    std::string Name() const override { return "identity"; }
    nlohmann::json Params() const override { return IdentityOptions{}; }

protected:
    AlignResult DoAlign(const PointCloud&, const PointCloud&, const AlignContext&) override {
        AlignResult r;
        r.stop_reason = "no_op";
        return r;
    }
};

}  // namespace

MethodInfo IdentityMethodInfo() {
    MethodInfo info;
    info.name = "identity";
    info.summary = "no motion (returns I); the floor every method must beat";
    info.defaults = IdentityOptions{};
    info.create = [](const nlohmann::json& j) -> std::unique_ptr<RegistrationMethod> {
        ParseOptions<IdentityOptions>(j, "identity");
        return std::make_unique<IdentityMethod>();
    };
    return info;
}

}  // namespace regbench
