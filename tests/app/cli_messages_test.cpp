// Issue 55, item 8: messages and exit codes of the CLI at its edges.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/testing/cli.hpp"
#include "tests/testing/files.hpp"

namespace regbench {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::RunCli;

// `inspect --json` on a pair file whose path is not UTF-8 ended in a raw nlohmann
// "type_error.316". Expected: exit 0 and valid JSON (the byte shown as U+FFFD), the same
// summary as the file under a UTF-8 name.
TEST(CliMessages, InspectJsonPrintsAPathThatIsNotUtf8) {
    const fs::path dir = testing::FreshTempDir("inspect_bytes");
    const std::string plain = testing::SmallPairFile((dir / "p.h5").string(), 2);
    const std::string odd = (dir / "p\xff.h5").string();
    fs::copy_file(plain, odd);
    const CliResult a = RunCli("inspect --json '" + plain + "'");
    const CliResult b = RunCli("inspect --json '" + odd + "'");
    ASSERT_EQ(a.exit_code, 0) << a.output;
    ASSERT_EQ(b.exit_code, 0) << b.output;
    const nlohmann::json ja = nlohmann::json::parse(a.output);
    const nlohmann::json jb = nlohmann::json::parse(b.output);
    EXPECT_EQ(jb.at("summary"), ja.at("summary"));
    EXPECT_EQ(jb.at("file").get<std::string>(), (dir / "p\xef\xbf\xbd.h5").string());
    fs::remove_all(dir);
}

}  // namespace
}  // namespace regbench
