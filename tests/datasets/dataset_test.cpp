#include "datasets/dataset.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>

#include "core/usage_error.hpp"
#include "tests/datasets/test_files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;
using testing::ExpectThrowsWith;
using testing::FreshDir;
using testing::H5Dataset;
using testing::TetraOff;
using testing::WriteH5;
using testing::WriteText;

constexpr double kTol = 1e-9;

std::set<std::string> CategoriesOf(const Dataset& d) {
    std::set<std::string> out;
    for (std::size_t i = 0; i < d.size(); ++i) out.insert(d.Get(i).category);
    return out;
}

std::set<std::string> NamesOf(const Dataset& d) {
    std::set<std::string> out;
    for (std::size_t i = 0; i < d.size(); ++i) out.insert(d.Get(i).name);
    return out;
}

DatasetOptions RepoData() {
    DatasetOptions o;
    const char* root = std::getenv("REGBENCH_SOURCE_DIR");
    o.data_dir = (fs::path(root != nullptr ? root : ".") / "data").string();
    return o;
}

// Values 0.01 * k: recognisable after the float round trip.
std::vector<double> Ramp(std::size_t n, double offset = 0.0) {
    std::vector<double> v(n);
    for (std::size_t k = 0; k < n; ++k) v[k] = offset + 0.01 * static_cast<double>(k);
    return v;
}

TEST(OpenDataset, CgalCorpusLoadsEveryMeshIntoTheUnitSphere) {
    const auto all = OpenDataset("cgal", "all", RepoData());
    EXPECT_EQ(all->Kind(), "cgal");
    ASSERT_GE(all->size(), 35u);
    ASSERT_LE(all->size(), 50u);
    for (std::size_t i = 0; i < all->size(); ++i) {
        const ShapeRecord r = all->Get(i);
        SCOPED_TRACE(r.name);
        ASSERT_TRUE(r.mesh.has_value());
        EXPECT_GE(r.mesh->faces.rows(), 800);
        EXPECT_NEAR(r.mesh->vertices.rowwise().norm().maxCoeff(), 1.0, kTol);
        EXPECT_EQ(all->Categories()[static_cast<std::size_t>(r.label)], r.category);
        EXPECT_GT(SurfaceArea(*r.mesh), 0.0);
    }
}

TEST(OpenDataset, CgalSplitsShareOrSeparateCategories) {
    const DatasetOptions o = RepoData();
    const auto train = OpenDataset("cgal", "train", o);
    const auto val = OpenDataset("cgal", "same_category/val", o);
    const auto test = OpenDataset("cgal", "same_category/test", o);
    EXPECT_EQ(CategoriesOf(*train), CategoriesOf(*test));
    EXPECT_EQ(CategoriesOf(*train).size(), train->Categories().size());
    std::set<std::string> names = NamesOf(*train);
    for (const auto* part : {val.get(), test.get()}) {
        for (const std::string& n : NamesOf(*part)) EXPECT_TRUE(names.insert(n).second) << n;
    }
    EXPECT_EQ(names.size(), OpenDataset("cgal", "all", o)->size());
    const auto cross_train = OpenDataset("cgal", "cross_category/train", o);
    const auto cross_test = OpenDataset("cgal", "cross_category/test", o);
    for (const std::string& c : CategoriesOf(*cross_test)) {
        EXPECT_EQ(CategoriesOf(*cross_train).count(c), 0u) << c;
    }
    EXPECT_GT(cross_train->size(), 10u);
    EXPECT_GT(cross_test->size(), 10u);
    ExpectThrowsWith<std::invalid_argument>([&] { OpenDataset("cgal", "official/train", o); },
                                            "official/train");
    DatasetOptions nowhere;
    nowhere.data_dir = (FreshDir() / "nothing").string();
    ExpectThrowsWith([&] { OpenDataset("cgal", "all", nowhere); }, nowhere.data_dir);
}

TEST(OpenDataset, ProceduralSplitSizesAndDeterminism) {
    DatasetOptions o;
    o.procedural_per_category = 5;
    o.seed = 9;
    EXPECT_EQ(OpenDataset("procedural", "all", o)->size(), 50u);
    EXPECT_EQ(OpenDataset("procedural", "train", o)->size(), 30u);
    EXPECT_EQ(OpenDataset("procedural", "val", o)->size(), 10u);
    EXPECT_EQ(OpenDataset("procedural", "test", o)->size(), 10u);
    const auto cross_train = OpenDataset("procedural", "cross_category/train", o);
    const auto cross_test = OpenDataset("procedural", "cross_category/test", o);
    EXPECT_EQ(cross_train->size(), 20u);
    EXPECT_EQ(OpenDataset("procedural", "cross_category/val", o)->size(), 5u);
    EXPECT_EQ(cross_test->size(), 25u);
    for (const std::string& c : CategoriesOf(*cross_test)) {
        EXPECT_EQ(CategoriesOf(*cross_train).count(c), 0u) << c;
    }
    const ShapeRecord a = cross_test->Get(3);
    EXPECT_EQ(a.mesh->vertices,
              OpenDataset("procedural", "cross_category/test", o)->Get(3).mesh->vertices);
    EXPECT_NEAR(a.mesh->vertices.rowwise().norm().maxCoeff(), 1.0, kTol);
    o.seed = 10;
    EXPECT_NE(a.mesh->vertices,
              OpenDataset("procedural", "cross_category/test", o)->Get(3).mesh->vertices);
    EXPECT_THROW(OpenDataset("procedural", "test", o)->Get(10), std::out_of_range);
}

TEST(OpenDataset, ModelNetOffTreeLabelsAndSplits) {
    const fs::path root = FreshDir() / "ModelNet40";
    const std::vector<std::string> classes = {"airplane", "bathtub", "cup", "desk"};
    for (const std::string& c : classes) {
        for (int k = 0; k < 5; ++k) {
            WriteText(root / c / "train" / (c + "_000" + std::to_string(k) + ".off"),
                      TetraOff(1.0 + k, /*modelnet_header=*/k % 2 == 0));
        }
        WriteText(root / c / "test" / (c + "_0100.off"), TetraOff(2.0));
    }
    // The parent folder of ModelNet40/ works too.
    const auto all = OpenDataset(root.parent_path().string(), "all");
    EXPECT_EQ(all->Kind(), "modelnet40");
    EXPECT_EQ(all->Categories(), classes);
    EXPECT_EQ(all->size(), 24u);
    const auto train = OpenDataset(root.string(), "same_category/train");
    ASSERT_EQ(train->size(), 8u);  // airplane, bathtub: 4 of 5 train files each
    EXPECT_EQ(train->Get(0).name, "airplane_0000");
    EXPECT_EQ(train->Get(4).label, 1);
    EXPECT_NEAR(train->Get(0).mesh->vertices.rowwise().norm().maxCoeff(), 1.0, kTol);
    const auto val = OpenDataset(root.string(), "val");
    ASSERT_EQ(val->size(), 2u);
    EXPECT_EQ(val->Get(1).name, "bathtub_0004");
    const auto test = OpenDataset(root.string(), "test");
    EXPECT_EQ(NamesOf(*test), (std::set<std::string>{"airplane_0100", "bathtub_0100"}));
    const auto cross = OpenDataset(root.string(), "cross_category/test");
    EXPECT_EQ(NamesOf(*cross), (std::set<std::string>{"cup_0100", "desk_0100"}));
    EXPECT_EQ(cross->Get(1).label, 3);
    EXPECT_EQ(OpenDataset(root.string(), "official/train")->size(), 20u);
    // A corrupt file fails when read, naming it.
    const std::string bad =
        WriteText(root / "desk" / "test" / "desk_0101.off", "OFF\n4 4 0\n0 0 0\n");
    const auto with_bad = OpenDataset(root.string(), "cross_category/test");
    ExpectThrowsWith([&] { with_bad->Get(2); }, bad);
}

TEST(OpenDataset, ModelNetHdf5ReleaseLabelsPointsAndSplits) {
    const fs::path dir = FreshDir() / "modelnet40_ply_hdf5_2048";
    const std::size_t n_train = 8, n_test = 4, p = 5;
    // Train labels 0,0,0,0,0,1,2,3: the 5th airplane (rank 4) is the validation item.
    WriteH5(dir / "ply_data_train0.h5",
            {{"data", {n_train, p, 3}, Ramp(n_train * p * 3)},
             {"normal", {n_train, p, 3}, Ramp(n_train * p * 3, 1.0)},
             {"label", {n_train, 1}, {0, 0, 0, 0, 0, 1, 2, 3}, H5T_STD_U8LE}});
    WriteH5(dir / "ply_data_test0.h5", {{"data", {n_test, p, 3}, Ramp(n_test * p * 3, 5.0)},
                                        {"label", {n_test, 1}, {0, 1, 2, 3}, H5T_STD_U8LE}});
    WriteText(dir / "shape_names.txt", "airplane\nbathtub\ncup\ndesk\n");
    const auto all = OpenDataset(dir.parent_path().string(), "all");
    EXPECT_EQ(all->Kind(), "modelnet40_h5");
    EXPECT_EQ(all->size(), 12u);
    EXPECT_EQ(all->Categories()[3], "desk");
    const ShapeRecord first = all->Get(1);
    ASSERT_EQ(first.points.rows(), 5);
    EXPECT_NEAR(first.points(0, 0), 0.01 * 15, 1e-6);  // row 1 starts at value index 5 * 3
    EXPECT_NEAR(first.normals(0, 0), 1.0 + 0.01 * 15, 1e-6);
    EXPECT_EQ(OpenDataset(dir.string(), "train")->size(), 5u);
    const auto val = OpenDataset(dir.string(), "val");
    ASSERT_EQ(val->size(), 1u);
    EXPECT_EQ(val->Get(0).name, "ply_data_train0/00004");
    const auto test = OpenDataset(dir.string(), "test");
    EXPECT_EQ(CategoriesOf(*test), (std::set<std::string>{"airplane", "bathtub"}));
    EXPECT_EQ(test->Get(0).normals.rows(), 0);
    const auto cross = OpenDataset(dir.string(), "cross_category/test");
    EXPECT_EQ(CategoriesOf(*cross), (std::set<std::string>{"cup", "desk"}));
    EXPECT_NEAR(cross->Get(0).points(0, 0), 5.0 + 0.01 * 30, 1e-6);

    // The official list files name paths relative to another root: the file name counts.
    WriteText(dir / "train_files.txt", "data/modelnet40_ply_hdf5_2048/ply_data_train0.h5\n");
    EXPECT_EQ(OpenDataset(dir.string(), "train")->size(), 5u);
    WriteText(dir / "test_files.txt", "data/modelnet40_ply_hdf5_2048/ply_data_test9.h5\n");
    ExpectThrowsWith([&] { OpenDataset(dir.string(), "test"); }, "test_files.txt");
}

TEST(OpenDataset, Hdf5RejectsTruncatedAndMalformedFilesNamingThem) {
    const fs::path dir = FreshDir() / "modelnet40_ply_hdf5_2048";
    const std::string good = WriteH5(dir / "ply_data_train0.h5",
                                     {{"data", {2, 4, 3}, Ramp(24)}, {"label", {2, 1}, {0, 1}}});
    fs::resize_file(good, fs::file_size(good) / 2);
    ExpectThrowsWith([&] { OpenDataset(dir.string(), "train"); }, good);
    const std::string bad_shape = WriteH5(dir / "ply_data_train0.h5",
                                          {{"data", {2, 12}, Ramp(24)}, {"label", {2, 1}, {0, 1}}});
    ExpectThrowsWith([&] { OpenDataset(dir.string(), "train"); }, bad_shape + ": dataset 'data'");
    const std::string bad_label = WriteH5(
        dir / "ply_data_train0.h5", {{"data", {2, 4, 3}, Ramp(24)}, {"label", {2, 1}, {0, 77}}});
    ExpectThrowsWith([&] { OpenDataset(dir.string(), "train"); }, bad_label + ": label 77");
    // Issue 27: a file of a few KB declaring (1e7, 2048, 3) floats (245 GB) ended in a bare
    // std::bad_alloc; the declared size is refused before allocation, naming file and dataset.
    const std::string huge = WriteH5(
        dir / "ply_data_train0.h5", {{"data", {10000000, 2048, 3}, {}}, {"label", {2, 1}, {0, 1}}});
    ASSERT_LT(fs::file_size(huge), 100000u);
    ExpectThrowsWith([&] { OpenDataset(dir.string(), "train"); },
                     huge + ": dataset 'data' declares shape [10000000, 2048, 3]");
    const std::string not_h5 = WriteText(dir / "other.h5", "plain text");
    ExpectThrowsWith([&] { OpenDataset(not_h5); }, not_h5);
}

TEST(OpenDataset, DeepGmrStyleFilesAndIclNuim) {
    const fs::path root = FreshDir();
    const fs::path icl = root / "icl_nuim";
    WriteH5(icl / "train" / "icl_nuim.h5", {{"points", {3, 6, 3}, Ramp(54)}});
    std::vector<double> transforms(2 * 16, 0.0);
    for (int s = 0; s < 2; ++s) {
        for (int d = 0; d < 4; ++d) transforms[static_cast<std::size_t>(s * 16 + d * 5)] = 1.0;
        transforms[static_cast<std::size_t>(s * 16 + 3)] = 0.5 * (s + 1);  // t_x
    }
    WriteH5(icl / "test" / "icl_nuim.h5", {{"source", {2, 6, 3}, Ramp(36)},
                                           {"target", {2, 6, 3}, Ramp(36, 2.0)},
                                           {"transform", {2, 4, 4}, transforms, H5T_IEEE_F64LE}});
    const auto train = OpenDataset(root.string(), "train");
    EXPECT_EQ(train->Kind(), "icl_nuim");
    ASSERT_EQ(train->size(), 3u);
    EXPECT_NEAR(train->Get(2).points(5, 2), 0.01 * 53, 1e-6);
    EXPECT_FALSE(train->Get(0).target.has_value());
    const auto test = OpenDataset(icl.string(), "test");
    ASSERT_EQ(test->size(), 2u);
    const ShapeRecord pair = test->Get(1);
    ASSERT_TRUE(pair.target.has_value() && pair.T_target_points.has_value());
    EXPECT_NEAR((*pair.T_target_points)(0, 3), 1.0, kTol);
    EXPECT_NEAR((*pair.target)(0, 0), 2.0 + 0.01 * 18, 1e-6);
    EXPECT_EQ(OpenDataset(root.string(), "all")->size(), 5u);
    // A single file opens on its own; a missing one is named.
    EXPECT_EQ(OpenDataset((icl / "test" / "icl_nuim.h5").string())->size(), 2u);
    fs::remove(icl / "test" / "icl_nuim.h5");
    ExpectThrowsWith([&] { OpenDataset(root.string(), "test"); }, (icl / "test").string());
    const std::string wrong = WriteH5(root / "wrong.h5", {{"clouds", {1, 2, 3}, Ramp(6)}});
    ExpectThrowsWith([&] { OpenDataset(wrong); }, wrong);
}

TEST(OpenDataset, SevenScenesLayout) {
    const fs::path root = FreshDir() / "7scene";
    const std::string ply_head =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n";
    WriteText(root / "7-scenes-chess" / "cloud_bin_0.ply", ply_head + "1 2 3\n4 5 6\n7 8 9\n");
    WriteText(root / "7-scenes-chess" / "cloud_bin_1.ply", ply_head + "0 0 0\n1 1 1\n2 2 2\n");
    WriteText(root / "7-scenes-office" / "cloud_bin_0.ply", ply_head + "3 3 3\n4 4 4\n5 5 5\n");
    const auto train = OpenDataset(root.parent_path().string(), "train");
    EXPECT_EQ(train->Kind(), "7scenes");
    ASSERT_EQ(train->size(), 2u);
    const ShapeRecord r = train->Get(0);
    EXPECT_EQ(r.name, "chess/cloud_bin_0");
    EXPECT_EQ(r.points.row(1), Eigen::RowVector3d(4, 5, 6));  // file order kept
    EXPECT_EQ(train->Categories()[static_cast<std::size_t>(r.label)], "chess");
    const auto test = OpenDataset(root.string(), "test");
    ASSERT_EQ(test->size(), 1u);
    EXPECT_EQ(test->Get(0).category, "office");
    EXPECT_THROW(OpenDataset(root.string(), "val"), std::invalid_argument);
    const std::string broken =
        WriteText(root / "7-scenes-office" / "cloud_bin_1.ply", ply_head + "3 3 3\n");
    ExpectThrowsWith([&] { OpenDataset(root.string(), "test")->Get(1); }, broken);
}

TEST(OpenDataset, GenericPointFilesAndErrors) {
    const fs::path root = FreshDir() / "scans";
    WriteText(root / "lab" / "a.xyz", "0 0 0\n1 0 0\n0 1 0\n");
    WriteText(root / "lab" / "b.xyz", "0 0 1\n1 0 1\n");
    WriteText(root / "office" / "c.off", TetraOff(3.0));
    const auto d = OpenDataset(root.string());
    EXPECT_EQ(d->Kind(), "points");
    ASSERT_EQ(d->size(), 3u);
    EXPECT_EQ(d->Categories(), (std::vector<std::string>{"lab", "office"}));
    EXPECT_EQ(d->Get(1).points.rows(), 2);
    EXPECT_EQ(d->Get(1).name, "lab/b");
    ASSERT_TRUE(d->Get(2).mesh.has_value());
    EXPECT_EQ(d->Get(2).label, 1);
    const auto single = OpenDataset((root / "lab" / "a.xyz").string());
    ASSERT_EQ(single->size(), 1u);
    EXPECT_EQ(single->Get(0).points.rows(), 3);
    EXPECT_THROW(OpenDataset(root.string(), "train"), std::invalid_argument);
    // Issue 54 item 1: `generate --split test` on a folder says which split it has, as a
    // usage error (exit 2).
    try {
        OpenDataset(root.string(), "test");
        ADD_FAILURE() << "split test of a folder accepted";
    } catch (const UsageError& e) {
        EXPECT_NE(std::string(e.what()).find("has only split 'all'"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(OpenDataset("procedural", "bogus"), std::invalid_argument);
    const std::string missing = (root / "nowhere").string();
    ExpectThrowsWith([&] { OpenDataset(missing); }, missing);
    const std::string bad = WriteText(root / "lab" / "c.xyz", "1 2 3\nnot a point\n");
    ExpectThrowsWith([&] { OpenDataset(root.string())->Get(2); }, bad + ":2");
}

}  // namespace
}  // namespace regbench
