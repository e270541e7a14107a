// The worked example of docs/adding-a-method.md, compiled and tested so the document cannot rot:
// a `centroid` method (not in the registry) that only translates the source's centre onto the
// target's. The block between the EXAMPLE markers is the document's baselines/centroid.cpp
// body verbatim; keep them in step.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/params.hpp"
#include "core/transform.hpp"
#include "runners/result_row.hpp"
#include "runners/runner.hpp"
#include "tests/testing/synthetic_pair_file.hpp"
#include "tests/testing/temp_dir_test.hpp"

namespace regbench {
namespace {

/// The JSON Schema `regbench methods --json` should print for the example, written by hand
/// from the JSON Schema 2020-12 keywords: the expected value of the generated one.
constexpr const char* kCentroidSchema = R"json({
  "$schema": "https://json-schema.org/draft/2020-12/schema",
  "title": "centroid",
  "description": "translation only: moves the source's centre onto the target's",
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "centre": {
      "type": "string",
      "description": "\"mean\" or \"median\" (per axis; robust to outliers)",
      "default": "mean",
      "enum": ["mean", "median"]
    },
    "step": {
      "type": "number",
      "description": "fraction of the offset applied",
      "default": 1.0,
      "exclusiveMinimum": 0.0,
      "maximum": 1.0
    }
  }
})json";

// EXAMPLE BEGIN
enum class Centre { kMean, kMedian };
REGBENCH_CHOICES(Centre, {{Centre::kMean, "mean"}, {Centre::kMedian, "median"}})

struct CentroidOptions {
    Centre centre = Centre::kMean;  ///< "mean" or "median"
    double step = 1.0;              ///< fraction of the offset applied

    template <class F>
    void Fields(F&& f) {
        f("centre", centre, "\"mean\" or \"median\" (per axis; robust to outliers)");
        f("step", step, "fraction of the offset applied");
    }
    void Validate(ParamCheck& c) const {
        c.Above("step", step, 0.0);
        c.AtMost("step", step, 1.0);
    }
    /// Two centres, O(N + M) (O(N log N) for the median): never refused at scale.
    CostClass Cost() const { return CostClass::kNearLinear; }
};

Eigen::Vector3d Centre3(const PointCloud& p, Centre how) {
    if (how == Centre::kMean) return p.colwise().mean().transpose();
    Eigen::Vector3d c;
    for (int k = 0; k < 3; ++k) {
        Eigen::VectorXd v = p.col(k);
        std::sort(v.data(), v.data() + v.size());
        c[k] = v[v.size() / 2];  // upper median for even sizes
    }
    return c;
}

AlignResult AlignCentroid(const CentroidOptions& o, const PointCloud& source,
                          const PointCloud& target, const AlignContext& /*context*/) {
    const Eigen::Vector3d offset = Centre3(target, o.centre) - Centre3(source, o.centre);
    AlignResult r;
    r.T_target_source = MakeTransform(Eigen::Matrix3d::Identity(), o.step * offset);
    r.stop_reason = "closed_form";
    return r;
}

MethodInfo CentroidMethodInfo() {
    return MakeMethodInfo<CentroidOptions>(
        "centroid", "translation only: moves the source's centre onto the target's", AlignCentroid);
}
// EXAMPLE END

/// Four points whose mean (1.5, 0, 0) and upper median (2, 0, 0) differ: x = 0, 1, 2, 3.
PointCloud Line() {
    PointCloud p(4, 3);
    p << 0, 0, 0, 1, 0, 0, 2, 0, 0, 3, 0, 0;
    return p;
}

TEST(ExampleMethod, RegistryEntryAndSchemaComeFromTheStruct) {
    const MethodInfo info = CentroidMethodInfo();
    EXPECT_EQ(info.name, "centroid");
    EXPECT_EQ(info.summary, "translation only: moves the source's centre onto the target's");
    EXPECT_EQ(info.schema, nlohmann::json::parse(kCentroidSchema));
    ASSERT_EQ(info.param_docs.size(), 2u);
    EXPECT_EQ(info.param_docs.at("step"), "fraction of the offset applied; range (0, 1]");
    EXPECT_EQ(info.param_docs.at("centre"),
              "\"mean\" or \"median\" (per axis; robust to outliers)");
    EXPECT_EQ(info.defaults, nlohmann::json({{"centre", "mean"}, {"step", 1.0}}));
    auto method = info.create({{"centre", "median"}});
    EXPECT_EQ(method->Name(), "centroid");
    EXPECT_EQ(method->Params(), nlohmann::json({{"centre", "median"}, {"step", 1.0}}));
}

TEST(ExampleMethod, AlignsCentresByHand) {
    // Target = source + (0, 2, -1) with the last point moved to x = 11: the mean moves by
    // (2, 2, -1) (8 / 4 in x), the upper median (third of 0, 1, 2, 11) stays at x = 2.
    const PointCloud source = Line();
    PointCloud target = source.rowwise() + Eigen::RowVector3d(0, 2, -1);
    target(3, 0) = 11.0;
    const MethodInfo info = CentroidMethodInfo();
    const AlignResult mean = info.create({})->Align(source, target);
    const Eigen::Vector3d t_mean = mean.T_target_source.block(0, 3, 3, 1);
    EXPECT_TRUE(t_mean.isApprox(Eigen::Vector3d(2, 2, -1))) << t_mean.transpose();
    const AlignResult median =
        info.create({{"centre", "median"}, {"step", 0.5}})->Align(source, target);
    const Eigen::Vector3d t_median = median.T_target_source.block(0, 3, 3, 1);
    EXPECT_TRUE(t_median.isApprox(Eigen::Vector3d(0, 1, -0.5))) << t_median.transpose();
}

TEST(ExampleMethod, BadParametersNameTheParameter) {
    const MethodInfo info = CentroidMethodInfo();
    for (const auto& [params, name] : std::vector<std::pair<nlohmann::json, std::string>>{
             {{{"centre", "mode"}}, "'centre' must be one of \"mean\", \"median\""},
             {{{"step", 0.0}}, "'step' must be > 0.0, got 0.0"},
             {{{"step", 1.5}}, "'step' must be <= 1.0, got 1.5"},
             {{{"step", "half"}}, "'step' expects number"},
             {{{"stride", 1}}, "unknown parameter 'stride'"},
             {nlohmann::json::array(), "parameters must be a JSON object"}}) {
        try {
            info.create(params);
            ADD_FAILURE() << params.dump() << " was accepted";
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
            EXPECT_EQ(std::string(e.what()).rfind("centroid: ", 0), 0u) << e.what();
        }
    }
}

class ExampleMethodRun : public testing::TempDirTest {};

TEST_F(ExampleMethodRun, RunsOnA40000PointPairFileBecauseTheScaleGuardAsksTheMethod) {
    // The runner takes the method as a caller-supplied one with its registry entry's create and
    // cost: as registered, the scale guard asks CentroidOptions::Cost (near-linear) and runs it
    // on 40,000 points; declared quadratic, the same run is refused before any output exists.
    const std::string pairs = Path("pairs.h5");
    const Eigen::Vector3d t(0.5, 0.25, -1.0);
    testing::WriteSyntheticPairFile(pairs, 1, 40000, 11, 1, [&](int) {
        return MakeTransform(Eigen::Matrix3d::Identity(), t);
    });
    const MethodInfo info = CentroidMethodInfo();
    RunOptions run;
    run.pairs_path = pairs;
    run.out_path = Path("rows.jsonl");
    run.progress = false;
    run.methods = {{"centroid", info.defaults}};
    ExternalMethod external;
    external.create = [info] { return info.create(nlohmann::json::object()); };
    external.cost = info.cost;
    run.external_methods["centroid"] = external;
    RunBenchmark(run);
    const auto rows = ReadResultRows(run.out_path);
    ASSERT_EQ(rows.size(), 1u);
    EXPECT_EQ(rows[0].result.status, AlignStatus::kOk) << rows[0].result.message;

    run.out_path = Path("refused.jsonl");
    run.external_methods["centroid"].cost = [](const nlohmann::json&) {
        return CostClass::kQuadratic;
    };
    EXPECT_THROW(RunBenchmark(run), std::runtime_error);
    EXPECT_FALSE(std::filesystem::exists(run.out_path));
}

}  // namespace
}  // namespace regbench
