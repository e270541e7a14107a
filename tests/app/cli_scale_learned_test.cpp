// Issue 54 item 1's acceptance for a learned method: OGMM (the shipped object checkpoint,
// data/models/ogmm) on the same clouds at unit scale and in millimetres (x150, `generate --scale
// 150`). The millimetre pairs lie outside the training frame and are normalised (x -> (x - c) / s,
// c and s the source's centroid and radius; docs/learned-methods.md, "Scale and normalisation"),
// the unit ones are run as given, so the network sees the crops in two frames that differ by a
// shift of about the crop's offset and a factor of about 1 / 0.9: the two runs are not the same
// computation and agree statistically, not bit for bit. The expected relation is the hand
// derivation of tests/app/scale_corpus.hpp (a similarity preserves angles), with the translation
// error in millimetres 150 times the unit one. Measured differences of the means: 1.2 deg in
// rre and 11% in rte on the 21 pairs of docs/learned-methods.md, 0.67 deg and 12% on these 8;
// the tolerance (3 deg, 30%) is about 2.5 times the former and far below what the millimetre
// pairs gave without normalisation (OGMM's MAE(R) 31 against 8.6).
#include <gtest/gtest.h>

#include "tests/app/scale_corpus.hpp"

namespace regbench {
namespace {

TEST(CliScaleLearned, OgmmOnTheMillimetreCopyMatchesUnitScaleThroughNormalisation) {
    const std::filesystem::path dir = testing::FreshTempDir("cli_scale_learned");
    testing::RunUnitAndMillimetres(dir, 4, 8, "ogmm");
    const auto unit = testing::RowsByMethod((dir / "unit.jsonl").string()).at("ogmm");
    const auto mm = testing::RowsByMethod((dir / "mm.jsonl").string()).at("ogmm");
    ASSERT_EQ(unit.size(), 8u);
    ASSERT_EQ(mm.size(), 8u);
    for (std::size_t k = 0; k < mm.size(); ++k) {
        EXPECT_EQ(unit[k].status, Status::kOk) << unit[k].result.message;
        EXPECT_EQ(mm[k].status, Status::kOk) << mm[k].result.message;
        // Every millimetre pair was mapped into the unit sphere, by the source's own radius
        // (about 150 times that of a unit-sphere crop).
        ASSERT_TRUE(mm[k].result.extra.contains("normalization")) << "pair " << k;
        const double s = mm[k].result.extra["normalization"]["scale"].get<double>();
        EXPECT_GT(s, 0.3 * testing::kMillimetres) << "pair " << k;
        EXPECT_LT(s, 1.5 * testing::kMillimetres) << "pair " << k;
    }
    const auto rre = [](const PairMetrics& p) { return p.rre; };
    const auto rte = [](const PairMetrics& p) { return p.rte; };
    EXPECT_NEAR(testing::MeanOf(mm, rre), testing::MeanOf(unit, rre), 3.0);
    const double unit_rte = testing::MeanOf(unit, rte);
    EXPECT_NEAR(testing::MeanOf(mm, rte) / testing::kMillimetres, unit_rte, 0.3 * unit_rte);
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace regbench
