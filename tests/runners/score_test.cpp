#include "runners/score.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

#include "core/file_lock.hpp"
#include "protocols/pair_file.hpp"
#include "runners/result_row.hpp"
#include "runners/runner.hpp"
#include "tests/testing/synthetic_pair_file.hpp"
#include "tests/testing/temp_dir_test.hpp"

namespace regbench {
namespace {

class ScoreTest : public testing::PairFileTest {
protected:
    ScoreTest()
        : PairFileTest(4, 60, 20, 5, [](int k) {
              return MakeTransform(RotationXyzProductDeg(4.0 * k, -3.0, 6.0), {0.02 * k, 0.01, 0});
          }) {}
    void Write(const std::string& name, const std::string& text) const {
        std::ofstream(Path(name)) << text;
    }
    ScoreOptions Options(const std::string& transforms, const std::string& method) const {
        ScoreOptions o;
        o.pairs_path = pairs_;
        o.transforms_path = Path(transforms);
        o.method = method;
        o.out_path = Path("scored.jsonl");
        // Most files here are written by hand without a content hash; the refusal of such
        // files is tested on its own (TransformsWithoutAHashAreRefusedUnlessAllowed).
        o.allow_unhashed = true;
        return o;
    }
    /// Runs `method` with `run` and returns its rows.
    std::vector<nlohmann::json> RunRows(const std::string& method) const {
        RunOptions o;
        o.pairs_path = pairs_;
        o.methods = ParseMethodSpecs(method, {});
        o.out_path = Path("run.jsonl");
        o.progress = false;
        RunBenchmark(o);
        return ReadJsonl(o.out_path);
    }
};

/// The CSV line a user's script would write for one row: pair, top 3 rows, seconds.
std::string CsvLine(const nlohmann::json& row) {
    const Transform T = TransformFromJson(row["transform"]);
    std::string line = std::to_string(row["pair"].get<std::size_t>());
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) line += fmt::format(",{:.17g}", T(r, c));
    }
    return line + fmt::format(",{:.17g}\n", row["seconds"].get<double>());
}

/// The keys `score` cannot know about an external method (its internals).
/// What only the method's own call knows (internals) or only a run measures (CPU time of the
/// call, the machine's load): a transform file carries neither, so score leaves them empty.
void DropMethodInternals(nlohmann::json& row) {
    for (const char* key :
         {"iterations", "stop_reason", "extra", "message", "cpu_seconds", "machine", "timeout"}) {
        row.erase(key);
    }
}

TEST_F(ScoreTest, ScoredCsvRowsEqualWhatRunWritesForTheSameTransforms) {
    const auto run_rows = RunRows("icp");
    ASSERT_EQ(run_rows.size(), 4u);
    std::string csv = "pair,t00,t01,t02,t03,t10,t11,t12,t13,t20,t21,t22,t23,seconds\n";
    for (auto it = run_rows.rbegin(); it != run_rows.rend(); ++it)
        csv += CsvLine(*it);  // any order
    Write("t.csv", csv);
    ScoreOptions o = Options("t.csv", "icp");
    o.params = run_rows[0]["params"];
    const ScoreSummary s = ScoreTransforms(o);
    EXPECT_EQ(s.rows, 4u);
    EXPECT_EQ(s.missing, 0u);
    const auto scored = ReadJsonl(o.out_path);
    ASSERT_EQ(scored.size(), run_rows.size());
    for (std::size_t k = 0; k < scored.size(); ++k) {
        std::set<std::string> run_keys, score_keys;
        for (const auto& item : run_rows[k].items()) {
            // run-level provenance: the machine's load and the --timeout the call ran under
            if (item.key() != "machine" && item.key() != "timeout") run_keys.insert(item.key());
        }
        for (const auto& item : scored[k].items()) score_keys.insert(item.key());
        EXPECT_EQ(run_keys, score_keys) << "row " << k;  // one schema
        nlohmann::json a = run_rows[k];
        nlohmann::json b = scored[k];
        DropMethodInternals(a);
        DropMethodInternals(b);
        EXPECT_EQ(a, b) << "row " << k;
    }
}

TEST_F(ScoreTest, JsonlFromAnotherLanguageAndMissingPairs) {
    // Written by hand, as a Python script would: pair 1 rotated 90 deg about z, pair 3 absent.
    Write("t.jsonl",
          "{\"pair\": 0, \"transform\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], \"seconds\": "
          "0.5}\n"
          "{\"pair\": 1, \"transform\": [[0,-1,0,0.1],[1,0,0,0],[0,0,1,0],[0,0,0,1]]}\n"
          "{\"pair\": 2, \"transform\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], \"seconds\": "
          "0.25}\n");
    const ScoreOptions o = Options("t.jsonl", "mine");
    const ScoreSummary s = ScoreTransforms(o);
    EXPECT_EQ(s.rows, 4u);
    EXPECT_EQ(s.missing, 1u);
    const auto rows = ReadResultRows(o.out_path);
    ASSERT_EQ(rows.size(), 4u);
    EXPECT_EQ(rows[0].status, Status::kOk);
    EXPECT_EQ(rows[0].result.seconds, 0.5);
    EXPECT_EQ(rows[1].method, "mine");
    EXPECT_EQ(rows[1].result.T_target_source(0, 3), 0.1);
    EXPECT_EQ(rows[3].status, Status::kMissing);
    EXPECT_EQ(rows[3].result.T_target_source, Transform::Identity());
    const PairSet set = ReadPairFile(pairs_);
    // Metrics are those of the given transform against the pair's ground truth.
    const PairMetrics m = MotionMetrics(set.pairs[1].T_gt, rows[1].result.T_target_source);
    EXPECT_DOUBLE_EQ(rows[1].metrics.mae_r, m.mae_r);
    EXPECT_DOUBLE_EQ(rows[1].metrics.rre, m.rre);
    EXPECT_EQ(rows[1].euler, EulerConvention::kZyx);
}

/// Expects ScoreTransforms(o) to throw std::runtime_error containing `needle`, writing nothing.
void ExpectError(const ScoreOptions& o, const std::string& needle);

TEST_F(ScoreTest, RescoringARunResultFileKeepsOnlyTheNamedMethod) {
    RunRows("identity");
    std::filesystem::copy_file(Path("run.jsonl"), Path("old.jsonl"));
    ScoreOptions o = Options("old.jsonl", "identity");
    o.euler = EulerConvention::kXyz;
    EXPECT_EQ(ScoreTransforms(o).missing, 0u);
    std::filesystem::remove(Path("scored.jsonl"));
    // Issue 41: a --method the file holds no rows of wrote 4 `missing` rows (scored as the
    // identity), exit 0; it is refused naming the methods the file holds.
    ExpectError(Options("old.jsonl", "icp"),
                "old.jsonl: no rows of method 'icp'; it holds rows of 'identity'");
}

TEST_F(ScoreTest, TransformsWithoutAHashAreRefusedUnlessAllowed) {
    // Issue 41: a transforms file that records no content hash scored against any pair file,
    // silently measuring against another file's ground truth when it was not computed there.
    Write("plain.csv", "0,1,0,0,0,0,1,0,0,0,0,1,0\n");
    ScoreOptions strict = Options("plain.csv", "mine");
    strict.allow_unhashed = false;
    ExpectError(strict, "plain.csv:1: the transform records no content hash");
    ExpectError(strict, "--allow-unhashed");
    EXPECT_EQ(ScoreTransforms(Options("plain.csv", "mine")).missing, 3u);  // allowed
}

void ExpectError(const ScoreOptions& o, const std::string& needle) {
    try {
        ScoreTransforms(o);
        FAIL() << "expected an error containing " << needle;
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(o.out_path)) << "half-written output";
}

TEST_F(ScoreTest, InvalidFilesAreRejectedNamingFileAndLine) {
    const std::string id = ",1,0,0,0,0,1,0,0,0,0,1,0\n";
    struct Case {
        const char* file;
        std::string text;
        const char* needle;  ///< part of the expected error
    };
    const Case cases[] = {
        {"dup.csv", "0" + id + "1" + id + "0" + id, "dup.csv:3: pair 0 given twice (first at"},
        {"range.csv", "0" + id + "4" + id, "range.csv:2: pair 4 is out of range"},
        {"scaled.csv", "0,2,0,0,0,0,2,0,0,0,0,2,0\n",
         "scaled.csv:1: transform of pair 0 is not a rotation"},
        {"mirror.csv", "0,-1,0,0,0,0,1,0,0,0,0,1,0\n", "det R = -1"},
        {"short.csv", "0,1,0,0\n", "short.csv:1: expected 13 or 14 fields"},
        {"fifteen.csv", "0,1,0,0,0,0,1,0,0,0,0,1,0,0,0\n", "or 17 or 18 (pair,t00,...,t33"},
        {"text.csv", "0,1,0,0,0,0,1,0,0,0,0,1,abc\n", "field 13 ('abc') is not a number"},
        {"bad.jsonl", "{\"pair\": 0, \"transform\": [[1,0,0],[0,1,0],[0,0,1]]}\n",
         "bad.jsonl:1: transform is not 4x4"},
        {"t.txt", "", "must end in .jsonl (or .json), .csv, .log (3DMatch) or .npy (NumPy)"},
        {"full.csv", "0,1,0,0,0,0,1,0,0,0,0,1,0,0,0,0.5,1\n",
         "full.csv:1: transform of pair 0 has a bottom row other than (0, 0, 0, 1)"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.file);
        Write(c.file, c.text);
        ExpectError(Options(c.file, "m"), c.needle);
    }
}

// Issue 54 item 6: the formats other tools write. The expected matrices are written by hand:
// pair k gets Rz(90 deg)^k with translation (0.5 k, -0.25, 1), exact in float32 and float64.
Transform HandTransform(int k) {
    Transform T = Transform::Identity();
    const int c[4] = {1, 0, -1, 0};  // cos(90 k deg)
    const int s[4] = {0, 1, 0, -1};  // sin(90 k deg)
    T(0, 0) = c[k];
    T(0, 1) = -s[k];
    T(1, 0) = s[k];
    T(1, 1) = c[k];
    T(0, 3) = 0.5 * k;
    T(1, 3) = -0.25;
    T(2, 3) = 1.0;
    return T;
}

/// A .npy file as numpy.lib.format writes version 1.0: magic, version, little-endian uint16
/// header length, the header dict padded with spaces and a newline to a multiple of 64 bytes,
/// then the data.
std::string NpyFile(const std::string& descr, const std::string& fortran, const std::string& shape,
                    const std::string& data) {
    std::string dict = "{'descr': '" + descr + "', 'fortran_order': " + fortran +
                       ", 'shape': " + shape + ", }";
    const std::size_t total = ((10 + dict.size() + 1 + 63) / 64) * 64;
    dict += std::string(total - 10 - dict.size() - 1, ' ') + "\n";
    std::string out = "\x93NUMPY";
    out += '\x01';
    out += '\x00';
    out += static_cast<char>(dict.size() & 0xff);
    out += static_cast<char>(dict.size() >> 8);
    return out + dict + data;
}

/// The little-endian bytes of the 4 hand transforms, C order, as float32 or float64.
std::string HandTransformBytes(bool float32) {
    std::string out;
    for (int k = 0; k < 4; ++k) {
        const Transform T = HandTransform(k);
        for (int r = 0; r < 4; ++r) {
            for (int c = 0; c < 4; ++c) {
                unsigned char b[8];
                std::uint64_t raw = 0;
                if (float32) {
                    const float f = static_cast<float>(T(r, c));
                    std::uint32_t u = 0;
                    std::memcpy(&u, &f, 4);
                    raw = u;
                } else {
                    std::memcpy(&raw, &T(r, c), 8);
                }
                const int n = float32 ? 4 : 8;
                for (int i = 0; i < n; ++i) b[i] = static_cast<unsigned char>(raw >> (8 * i));
                out.append(reinterpret_cast<const char*>(b), static_cast<std::size_t>(n));
            }
        }
    }
    return out;
}

TEST_F(ScoreTest, NumpyLogAndFullCsvFilesGiveTheHandWrittenTransformsInPairOrder) {
    // The header numpy 1.24.2 writes for np.save(f, T) with T = np.zeros((4, 4, 4), "<f4")
    // (/usr/bin/python3; the first 128 bytes of the file, verbatim): NpyFile builds the same.
    const std::string numpy_header =
        std::string("\x93NUMPY\x01\x00v\x00", 10) +
        "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4, 4), }" + std::string(55, ' ') +
        "\n";
    ASSERT_EQ(numpy_header.size(), 128u);
    EXPECT_EQ(NpyFile("<f4", "False", "(4, 4, 4)", ""), numpy_header);
    Write("t32.npy", NpyFile("<f4", "False", "(4, 4, 4)", HandTransformBytes(true)));
    Write("t64.npy", NpyFile("<f8", "False", "(4, 4, 4)", HandTransformBytes(false)));
    // 3DMatch .log: "i j n" then the 4 rows, tab- or space-separated, as the toolbox writes.
    std::string log, csv = "pair,t00,t01,t02,t03,t10,t11,t12,t13,t20,t21,t22,t23,t30,t31,t32,t33\n";
    for (int k = 0; k < 4; ++k) {
        const Transform T = HandTransform(k);
        log += fmt::format("{}\t{}\t 5\n", k, k + 1);
        csv += std::to_string(k);
        for (int r = 0; r < 4; ++r) {
            log += fmt::format("{:.8e} {:.8e} {:.8e} {:.8e}\n", T(r, 0), T(r, 1), T(r, 2), T(r, 3));
            for (int c = 0; c < 4; ++c) csv += fmt::format(",{}", T(r, c));
        }
        csv += "\n";
    }
    Write("t.log", log);
    Write("t16.csv", csv);
    for (const char* file : {"t32.npy", "t64.npy", "t.log", "t16.csv"}) {
        SCOPED_TRACE(file);
        const ScoreOptions o = Options(file, "ext");
        const ScoreSummary summary = ScoreTransforms(o);
        EXPECT_EQ(summary.rows, 4u);
        EXPECT_EQ(summary.missing, 0u);
        const auto rows = ReadResultRows(o.out_path);
        ASSERT_EQ(rows.size(), 4u);
        const PairSet set = ReadPairFile(pairs_);
        for (std::size_t k = 0; k < 4; ++k) {
            EXPECT_EQ(rows[k].status, Status::kOk);
            EXPECT_EQ(rows[k].result.T_target_source, HandTransform(static_cast<int>(k))) << k;
            EXPECT_EQ(rows[k].result.seconds, 0.0);
            const PairMetrics m = MotionMetrics(set.pairs[k].T_gt, HandTransform(static_cast<int>(k)));
            EXPECT_DOUBLE_EQ(rows[k].metrics.rre, m.rre) << k;
        }
        std::filesystem::remove(o.out_path);
    }
}

TEST_F(ScoreTest, BadLogAndNpyFilesAreRefusedNamingTheFileAndTheProblem) {
    const std::string rec = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
    const std::string good_data = HandTransformBytes(false);
    struct Case {
        const char* file;
        std::string text;
        const char* needle;
    };
    const Case cases[] = {
        {"three.log", "0 1 4\n" + rec + "1 2 4\n" + rec + "2 3 4\n" + rec,
         "three.log: holds 3 records but the pair file has 4 pairs"},
        {"five.log", "0 1 4\n" + rec + "0 2 4\n" + rec + "0 3 4\n" + rec + "1 2 4\n" + rec +
                         "1 3 4\n" + rec,
         "five.log:21: record 5 but the pair file has 4 pairs"},
        {"cut.log", "0 1 4\n1 0 0 0\n0 1 0 0\n", "cut.log:1: the record ends after 2 of the 4 rows"},
        {"header.log", "0 1\n" + rec, "header.log:1: expected a record header 'i j n'"},
        {"frac.log", "0 1.5 4\n" + rec, "frac.log:1: expected a record header 'i j n'"},
        {"row.log", "0 1 4\n1 0 0\n", "row.log:1 (4 numbers), got 3 fields"},  // row 1 of 4
        {"word.log", "0 1 4\n1 0 zero 0\n", "word.log:2: field 3 ('zero') is not a number"},
        {"scaled.log", "0 1 4\n2 0 0 0\n0 2 0 0\n0 0 2 0\n0 0 0 1\n",
         "scaled.log:1: transform of pair 0 is not a rotation"},
        {"magic.npy", "not numpy at all", "magic.npy: not a NumPy .npy file"},
        {"big.npy", NpyFile(">f8", "False", "(4, 4, 4)", good_data),
         "big.npy: dtype '>f8' is not little-endian float64"},
        {"int.npy", NpyFile("<i8", "False", "(4, 4, 4)", good_data), "dtype '<i8'"},
        {"fortran.npy", NpyFile("<f8", "True", "(4, 4, 4)", good_data),
         "fortran.npy: array is in Fortran order"},
        {"shape.npy", NpyFile("<f8", "False", "(4, 16)", good_data),
         "shape.npy: array has shape (4, 16); expected (P, 4, 4)"},
        {"count.npy", NpyFile("<f8", "False", "(3, 4, 4)", good_data.substr(0, 3 * 128)),
         "count.npy: holds 3 transforms but the pair file has 4 pairs"},
        {"short.npy", NpyFile("<f8", "False", "(4, 4, 4)", good_data.substr(0, 500)),
         "short.npy: holds 500 data bytes; shape (4, 4, 4) of '<f8' needs 512"},
        {"nan.npy", NpyFile("<f8", "False", "(4, 4, 4)", [&] {
             std::string d = good_data;
             const double nan = std::nan("");
             std::memcpy(&d[2 * 128 + 8], &nan, 8);  // pair 2, entry (0, 1)
             return d;
         }()),
         "nan.npy[2]: transform of pair 2 has non-finite entries"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.file);
        Write(c.file, c.text);
        ExpectError(Options(c.file, "m"), c.needle);
    }
    // A .npy cannot record the pair file's hash: without --allow-unhashed it is refused, and
    // the message says what to pass.
    Write("ok.npy", NpyFile("<f8", "False", "(4, 4, 4)", good_data));
    ScoreOptions strict = Options("ok.npy", "m");
    strict.allow_unhashed = false;
    ExpectError(strict, "ok.npy[0]: the transform records no content hash");
    ExpectError(strict, "a .npy cannot record one");
}

TEST_F(ScoreTest, TransformsOfAnotherPairFileAreRefusedByTheirContentHash) {
    // Issue 26: transforms computed on another pair file scored MAE(R) 18.58 instead of 11.68
    // and exit 0. The hash each transform records must be the scored file's
    // (PairSetContentHash, as run writes in data.content_hash).
    const std::string hash = DataTagOf(pairs_, ReadPairFile(pairs_)).content_hash;
    const std::string identity = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
    Write("ok.jsonl",
          "{\"pair\": 0, \"content_hash\": \"" + hash + "\", \"transform\": " + identity + "}\n");
    EXPECT_EQ(ScoreTransforms(Options("ok.jsonl", "mine")).missing, 3u);
    std::filesystem::remove(Path("scored.jsonl"));
    Write("other.jsonl",
          "{\"pair\": 0, \"content_hash\": \"fnv1a64:0123456789abcdef\", "
          "\"transform\": " +
              identity + "}\n");
    ExpectError(Options("other.jsonl", "mine"),
                "other.jsonl:1: the transform was computed on "
                "the pair file with content hash "
                "fnv1a64:0123456789abcdef");
    // CSV (and JSONL) take it as a header comment.
    Write("other.csv",
          "# content_hash: fnv1a64:0123456789abcdef\npair,t00\n0,1,0,0,0,0,1,0,0,0,0,"
          "1,0\n");
    ExpectError(Options("other.csv", "mine"), "other.csv:3:");
    Write("ok.csv", "# content_hash: " + hash + "\n0,1,0,0,0,0,1,0,0,0,0,1,0\n");
    EXPECT_EQ(ScoreTransforms(Options("ok.csv", "mine")).missing, 3u);
    std::filesystem::remove(Path("scored.jsonl"));
    // A result file of another pair file (its rows carry data.content_hash) is refused too.
    RunRows("identity");
    auto rows = ReadJsonl(Path("run.jsonl"));
    std::ofstream(Path("foreign.jsonl")) << [&] {
        rows[0]["data"]["content_hash"] = "fnv1a64:ffff";
        return rows[0].dump();
    }() << "\n";
    ExpectError(Options("foreign.jsonl", "identity"), "fnv1a64:ffff");
}

TEST_F(ScoreTest, SimilaritiesNeedAllowScale) {
    // 2 Rz(90): rejected as rigid; with allow_scale the row has scale 2 and the rotation metrics
    // of Rz(90) itself (computed here by MotionMetrics on the unscaled matrix).
    Write("sim.csv", "0,0,-2,0,0,2,0,0,0,0,0,2,0\n");
    ScoreOptions o = Options("sim.csv", "m");
    ExpectError(o, "--allow-scale accepts s R");
    o.allow_scale = true;
    ScoreTransforms(o);
    const auto rows = ReadResultRows(o.out_path);
    EXPECT_DOUBLE_EQ(rows[0].result.scale, 2.0);
    const PairSet set = ReadPairFile(pairs_);
    const PairMetrics m = MotionMetrics(
        set.pairs[0].T_gt, MakeTransform(RotationZyxProductDeg(90, 0, 0), Eigen::Vector3d::Zero()));
    EXPECT_NEAR(rows[0].metrics.mae_r, m.mae_r, 1e-9);
    EXPECT_NEAR(rows[0].metrics.rre, m.rre, 1e-6);
}

TEST_F(ScoreTest, SlightlyNonOrthonormalFloat32OutputIsAccepted) {
    // A rotation printed with 7 significant digits (float32) is off by ~1e-7: within 1e-4.
    Write("f32.csv", "0,0.8660254,-0.5,0,0.1,0.5,0.8660254,0,0,0,0,1,0\n");
    EXPECT_EQ(ScoreTransforms(Options("f32.csv", "m")).missing, 3u);
}

// Issue 27: two `score`s on one --out both exited 0 and the last writer won. Expected: while
// another writer holds the output lock (here an OutputLock of this process, which flock
// treats as another holder), score is refused naming that pid and writes nothing.
TEST_F(ScoreTest, SecondWriterOfTheOutputIsRefused) {
    Write("t.jsonl", "{\"pair\": 0, \"transform\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}\n");
    const ScoreOptions o = Options("t.jsonl", "mine");
    const OutputLock holder(o.out_path);
    std::string err;
    try {
        ScoreTransforms(o);
    } catch (const std::exception& e) {
        err = e.what();
    }
    EXPECT_NE(err.find("pid " + std::to_string(::getpid())), std::string::npos) << err;
    EXPECT_FALSE(std::filesystem::exists(o.out_path));
}

}  // namespace
}  // namespace regbench
