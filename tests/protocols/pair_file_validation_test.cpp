// Every hostile pair file is refused with an error naming the file and the problem, before a
// large allocation; a pair file cannot be written over by a size-limited disk.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>

#include "protocols/pair_file.hpp"
#include "tests/testing/expect_throw.hpp"
#include "tests/testing/file_size_limit.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/hostile_pair_files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;

class HostilePairFile : public ::testing::TestWithParam<testing::HostileCase> {};

TEST_P(HostilePairFile, IsRefusedNamingFileAndProblem) {
    const testing::HostileCase& c = GetParam();
    const fs::path path = regbench::testing::TempPath("hostile_" + c.name + ".h5");
    testing::WriteHostile(path.string(), c);
    testing::ExpectThrowsWith([&] { ReadPairFile(path.string()); }, path.string(), c.expect);
    fs::remove(path);
}

INSTANTIATE_TEST_SUITE_P(Cases, HostilePairFile, ::testing::ValuesIn(testing::HostileCases()),
                         [](const auto& info) { return info.param.name; });

TEST(PairFileValidation, ProperRotationIsAccepted) {
    // A 30-degree rotation about z with a translation: rigid, so the reader keeps it.
    const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
    const testing::HostileCase ok{
        "ok", "", testing::SetTgt({c, -s, 0, 1, s, c, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1})};
    const fs::path path = regbench::testing::TempPath("valid_rotation.h5");
    testing::WriteHostile(path.string(), ok);
    const PairSet set = ReadPairFile(path.string());
    ASSERT_EQ(set.pairs.size(), 2u);
    EXPECT_DOUBLE_EQ(set.pairs[1].T_gt(1, 0), s);
    fs::remove(path);
}

TEST(PairFileValidation, FileSizeLimitLeavesNoPairFileAndNoSignal) {
    // RLIMIT_FSIZE in a child (SIGXFSZ ignored) stands in for a full disk: every HDF5 write,
    // flush or close past 16 KB fails with EFBIG.
    const fs::path dir = regbench::testing::TempPath("pairfile_fsize");
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string path = (dir / "big.h5").string();
    PairSet set;
    for (int k = 0; k < 10; ++k) {
        set.pairs.push_back(testing::SyntheticPair(500, k, Transform::Identity()));
    }
    const int status = testing::RunUnderFileSizeLimit<std::runtime_error>(
        16384, path, [&] { WritePairFile(path, set); });
    ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 3);
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(fs::is_empty(dir)) << "temporary left behind";
    fs::remove_all(dir);
}

// The fuzz regressions: the read must throw std::runtime_error whose message names the file.
using testing::ExpectThrowsWith;

TEST(PairFileValidation, FuzzFindingHugeMetadataAllocationIsRefused) {
    // Found by fuzz_pair_file (libFuzzer): a flipped header field makes HDF5 itself ask for a
    // 2^53-byte metadata buffer. The reader must refuse the file by name, not crash.
    const std::string path = "fuzz/corpus/pair_file/regression_hdf5_huge_metadata_alloc.h5";
    ExpectThrowsWith([&] { ReadPairFile(path); }, path);
}

TEST(PairFileValidation, FuzzFindingUseAfterFreeInsideHdf5IsRefused) {
    // Found by fuzz_pair_file under ASan: a damaged object header makes libhdf5 1.10 read freed
    // memory (H5O__msg_iterate_real). The file is read in a child process first, so in the
    // sanitizer build the child's death is what refuses it; in a plain build HDF5 reports an
    // error instead. Either way: an exception naming the file, never a crash of the caller.
    const std::string path = "fuzz/corpus/pair_file/regression_hdf5_use_after_free.h5";
    ExpectThrowsWith([&] { ReadPairFile(path); }, path);
    ExpectThrowsWith([&] { CountPairs(path); }, path);
}

TEST(PairFileValidation, OutputThatIsADirectoryIsRefused) {
    const fs::path dir = regbench::testing::TempPath("pairfile_dir_out");
    fs::create_directories(dir);
    PairSet set;
    set.pairs.push_back(testing::SyntheticPair(20, 1, Transform::Identity()));
    EXPECT_THROW(WritePairFile(dir.string(), set), std::runtime_error);
    EXPECT_TRUE(fs::is_directory(dir));
    EXPECT_TRUE(fs::is_empty(dir));
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench
