// Issue 55, item 7: a method whose transform had the last row [0.5, 0, 0, 1] (a Python method)
// got an `ok` row. Expected: RegistrationMethod::Align fails the call saying why, with the
// identity as its transform; a rigid transform (last row exactly or within 1e-6 of (0, 0, 0,
// 1)) stays ok.
#include "core/registration.hpp"

#include <gtest/gtest.h>

#include <string>

namespace regbench {
namespace {

/// Returns the transform it was given.
class Fixed : public RegistrationMethod {
public:
    explicit Fixed(Transform T) : T_(T) {}
    std::string Name() const override { return "fixed"; }
    nlohmann::json Params() const override { return nlohmann::json::object(); }

protected:
    AlignResult DoAlign(const PointCloud&, const PointCloud&, const AlignContext&) override {
        AlignResult r;
        r.T_target_source = T_;
        return r;
    }

private:
    Transform T_;
};

TEST(RegistrationMethod, ALastRowOtherThanHomogeneousFailsTheCall) {
    PointCloud cloud(4, 3);
    cloud << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
    Transform bad = Transform::Identity();
    bad(3, 0) = 0.5;
    const AlignResult r = Fixed(bad).Align(cloud, cloud);
    EXPECT_EQ(r.status, AlignStatus::kFailed);
    EXPECT_NE(r.message.find("last row is not (0, 0, 0, 1)"), std::string::npos) << r.message;
    EXPECT_TRUE(r.T_target_source.isIdentity());
    Transform scaled_w = Transform::Identity();
    scaled_w(3, 3) = 2.0;
    EXPECT_EQ(Fixed(scaled_w).Align(cloud, cloud).status, AlignStatus::kFailed);
    Transform nearly = Transform::Identity();
    nearly(0, 3) = 0.25;
    nearly(3, 3) = 1.0 + 1e-9;
    EXPECT_EQ(Fixed(nearly).Align(cloud, cloud).status, AlignStatus::kOk);
}

}  // namespace
}  // namespace regbench
