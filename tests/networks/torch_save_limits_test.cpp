// Issue 55, items 5 and 8, the file level of the torch.save reader: a 30 GB sparse file with a
// zip header was read whole (then the OOM killer), /proc/self/mem ended in a bare
// "basic_filebuf::underflow", and a zip whose version record is huge in "error: stoull".
// Expected: each refused with a std::runtime_error naming the file.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <string>

#include "networks/checkpoint/torch_save_reader.hpp"
#include "tests/testing/files.hpp"
#include "tests/testing/shell.hpp"

namespace regbench::networks {
namespace {
namespace fs = std::filesystem;

using testing::ErrorOf;

TEST(TorchSaveLimits, AFileBeyondTheSizeLimitIsRefusedBeforeItIsRead) {
    const fs::path dir = testing::FreshTempDir("torch_save_big");
    const fs::path big = dir / "big.pth";
    testing::WriteBytes(big, std::string("PK\x03\x04", 4));
    fs::resize_file(big, kMaxTorchSaveFileBytes + 1);  // sparse: no disk, no memory
    const std::string e = ErrorOf([&] { ReadTorchSaveFile(big.string()); });
    EXPECT_NE(e.find(big.string()), std::string::npos) << e;
    EXPECT_NE(e.find("is 2147483649 bytes, more than the 2147483648"), std::string::npos) << e;
    fs::remove_all(dir);
}

TEST(TorchSaveLimits, AnUnreadableFileIsNamed) {
    const std::string e = ErrorOf([] { ReadTorchSaveFile("/proc/self/mem"); });
    EXPECT_EQ(e.rfind("/proc/self/mem: ", 0), 0u) << e;
}

// Item 6: the reader checked its input by name and opened it afterwards, so a link flipped to a
// FIFO in between blocked it for ever. It now opens once without blocking and checks what it
// opened. (The flip itself cannot be timed from here; this checks that a FIFO, a folder and a
// device are refused by what was opened, promptly, and a regular file's hash is of the bytes
// read.)
TEST(TorchSaveLimits, TheOpenedFileIsTheOneCheckedAndRead) {
    const fs::path dir = testing::FreshTempDir("torch_save_kinds");
    const fs::path fifo = dir / "fifo.pth";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    EXPECT_NE(ErrorOf([&] { ReadTorchSaveFile(fifo.string()); })
                  .find(fifo.string() + ": not a regular file"),
              std::string::npos);
    EXPECT_NE(ErrorOf([&] { ReadTorchSaveFile(dir.string()); })
                  .find(dir.string() + ": is a directory"),
              std::string::npos);
    EXPECT_NE(ErrorOf([] { ReadTorchSaveFile("/dev/zero"); }).find("/dev/zero: not a regular file"),
              std::string::npos);
    StateDict sd = {{"w", torch::arange(6, torch::kFloat)}};
    const std::string bytes = WriteTorchSaveZip(sd);
    const fs::path pth = dir / "w.pth";
    testing::WriteBytes(pth, bytes);
    const TorchSaveContents c = ReadTorchSaveFile(pth.string());
    EXPECT_EQ(c.sha256, Sha256Hex(bytes));
    EXPECT_EQ(c.bytes, bytes.size());
    ASSERT_EQ(c.tensors.size(), 1u);
    EXPECT_TRUE(torch::equal(c.tensors[0].second, sd[0].second));
    fs::remove_all(dir);
}

TEST(TorchSaveLimits, AZipWithAHugeVersionRecordIsNamed) {
    const fs::path dir = testing::FreshTempDir("torch_save_version");
    const fs::path pth = dir / "version.pth";
    // Python's zipfile (standard library): the layout torch.save writes, with a version record
    // no 64-bit number holds.
    const auto [rc, out] = testing::RunShell(
        "python3 -c \"import zipfile, sys; z = zipfile.ZipFile(sys.argv[1], 'w'); "
        "z.writestr('archive/data.pkl', b'\\x80\\x02}q\\x00.'); "
        "z.writestr('archive/version', '9' * 40 + '\\n'); z.close()\" " +
        pth.string() + " 2>&1");
    ASSERT_EQ(rc, 0) << out;
    const std::string e = ErrorOf([&] { ReadTorchSaveFile(pth.string()); });
    EXPECT_EQ(e.rfind(pth.string() + ": ", 0), 0u) << e;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench::networks
