// ParamDocs (core/params.hpp): the line `regbench methods` prints per parameter is the meaning
// Fields gives, then the range Validate declares. Expected lines are written by hand from the
// interval notation ([ closed, ( open) of each Validate call below.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "core/params.hpp"

namespace regbench {
namespace {

/// One key per printed form.
struct RangeForms {
    int at_least = 1;
    double above = 0.5;
    double at_most = 0.0;
    double below = 0.0;
    double half_open = 0.0;
    double open_closed = 1.0;
    double finite_from_zero = 0.0;
    double finite_only = 0.0;
    double fraction_bound = 0.25;
    bool plain = false;

    template <class F>
    void Fields(F&& f) {
        f("at_least", at_least, "iterations");
        f("above", above, "radius [unit-sphere units]");
        f("at_most", at_most, "offset");
        f("below", below, "log weight");
        f("half_open", half_open, "outlier weight");
        f("open_closed", open_closed, "step fraction");
        f("finite_from_zero", finite_from_zero, "tolerance");
        f("finite_only", finite_only, "shift");
        f("fraction_bound", fraction_bound, "ratio");
        f("plain", plain, "a switch");
    }
    void Validate(ParamCheck& c) const {
        c.AtLeast("at_least", at_least, 1);
        c.Above("above", above, 0.0);
        c.AtMost("at_most", at_most, 2.0);
        c.Below("below", below, 0.0);
        c.AtLeast("half_open", half_open, 0.0);
        c.Below("half_open", half_open, 1.0);
        c.Above("open_closed", open_closed, 0.0);
        c.AtMost("open_closed", open_closed, 1.0);
        c.AtLeast("finite_from_zero", finite_from_zero, 0.0);
        c.Finite("finite_from_zero", finite_from_zero);
        c.Finite("finite_only", finite_only);
        c.AtLeast("fraction_bound", fraction_bound, 0.125);
        c.Require(true, "plain", "is never refused");  // a check, not a range: no suffix
    }
};

TEST(ParamDocs, MeaningThenTheRangeOfValidate) {
    const std::map<std::string, std::string> expected = {
        {"at_least", "iterations; range >= 1"},
        {"above", "radius [unit-sphere units]; range > 0"},
        {"at_most", "offset; range <= 2"},
        {"below", "log weight; range < 0"},
        {"half_open", "outlier weight; range [0, 1)"},
        {"open_closed", "step fraction; range (0, 1]"},
        {"finite_from_zero", "tolerance; range >= 0, finite"},
        {"finite_only", "shift; range finite"},
        {"fraction_bound", "ratio; range >= 0.125"},
        {"plain", "a switch"},
    };
    EXPECT_EQ(ParamDocs<RangeForms>(), expected);
}

TEST(ParamDocs, SchemaDescriptionIsTheMeaningAlone) {
    const nlohmann::json schema = ParamSchemaOf<RangeForms>("forms", "range forms");
    const nlohmann::json& p = schema.at("properties");
    EXPECT_EQ(p.at("open_closed").at("description"), "step fraction");
    EXPECT_EQ(p.at("open_closed").at("exclusiveMinimum"), 0.0);
    EXPECT_EQ(p.at("open_closed").at("maximum"), 1.0);
    EXPECT_EQ(p.at("finite_only").at("x-finite"), true);
    EXPECT_EQ(p.at("plain").at("description"), "a switch");
}

}  // namespace
}  // namespace regbench
