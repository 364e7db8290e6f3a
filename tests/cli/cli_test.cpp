// The command-line contract of DESIGN.md: --help and --version succeed on stdout, bad usage
// exits 2 with a one-line error on stderr, and no invocation dies of a signal.
#include "run_vtex.h"

#include <vtex/core/version.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using vtex::test::runVtex;

TEST(Cli, VersionPrintsTheProjectVersion) {
    const auto r = runVtex({"--version"});
    EXPECT_EQ(r.exitStatus, 0);
    EXPECT_NE(r.out.find(vtex::kVersion), std::string::npos) << r.out;
}

TEST(Cli, HelpGoesToStdoutAndNamesTheExitStatuses) {
    const auto r = runVtex({"--help"});
    EXPECT_EQ(r.exitStatus, 0);
    EXPECT_NE(r.out.find("Exit status"), std::string::npos) << r.out;
    EXPECT_TRUE(r.err.empty()) << r.err;
}

TEST(Cli, AnUnknownFlagIsBadUsage) {
    const auto r = runVtex({"--no-such-flag"});
    EXPECT_EQ(r.exitStatus, 2);
    EXPECT_NE(r.err.find("vtex: error:"), std::string::npos) << r.err;
}

TEST(Cli, AnUnknownSubcommandIsBadUsage) {
    const auto r = runVtex({"frobnicate"});
    EXPECT_EQ(r.exitStatus, 2);
    EXPECT_EQ(r.signal, 0);
}

TEST(Cli, NoSubcommandIsBadUsage) {
    const auto r = runVtex({});
    EXPECT_EQ(r.exitStatus, 2);
}

// The command line's manners (issue 17): `vtex help CMD` is `vtex CMD --help`; an unknown
// command is bad usage and names the nearest; --version names the commit.
TEST(Cli, HelpUnknownCommandsAndVersionAsGitDoes) {
    for (const std::string command : {"render", "sample", "run"}) {
        const auto help = runVtex({"help", command});
        const auto flag = runVtex({command, "--help"});
        EXPECT_EQ(help.exitStatus, 0) << help.err;
        EXPECT_EQ(help.out, flag.out) << command;
        EXPECT_NE(help.out.find("Usage: vtex " + command), std::string::npos) << help.out;
    }
    EXPECT_EQ(runVtex({"help"}).out, runVtex({"--help"}).out);
    const auto typo = runVtex({"rendr", "scene.toml"});
    EXPECT_EQ(typo.exitStatus, 2);
    EXPECT_NE(typo.err.find("unknown command 'rendr'; did you mean 'render'?"), std::string::npos) << typo.err;
    const auto far = runVtex({"-q", "xyzzy"});
    EXPECT_EQ(far.exitStatus, 2);
    EXPECT_NE(far.err.find("unknown command 'xyzzy'"), std::string::npos) << far.err;
    EXPECT_EQ(far.err.find("did you mean"), std::string::npos) << "nothing is near xyzzy: " << far.err;
    const auto version = runVtex({"--version"});
    EXPECT_EQ(version.exitStatus, 0);
    EXPECT_NE(version.out.find("(commit "), std::string::npos) << version.out;
}

// Found by fuzz_cli.py (fuzz/corpus-cli/regression_2): CLI11 quotes the arguments it did not
// expect, and an argument holding a newline split the error over two lines. Every message is
// one line, followed by the usage hint.
TEST(Cli, FuzzAnArgumentHoldingANewlineStillGivesAOneLineError) {
    const auto r = runVtex({"inspect", "a.vto", "new\nline.exr"});
    EXPECT_EQ(r.exitStatus, 2) << r.err;
    EXPECT_EQ(r.err, "vtex: error: The following argument was not expected: new line.exr\n"
                     "Run 'vtex --help' or 'vtex <command> --help' for usage.\n");
    const auto bad = runVtex({"render", "no\nsuch\r.toml", "-o", "x.exr"});
    EXPECT_EQ(bad.exitStatus, 3) << bad.err;
    EXPECT_EQ(vtex::test::lineCount(bad.err), 1u) << bad.err;
}

// Found by fuzz_cli.py (rechecking the first campaign's flags; fuzz/corpus-cli/regression_10):
// the unknown-command message (29ee2e2) quotes the argument and was printed without oneLine, so
// `vtex "new<LF>line.exr" …` split its error over two lines.
TEST(Cli, FuzzAnUnknownCommandHoldingANewlineIsOneLine) {
    const auto r = runVtex({"new\nline.exr", "16384", "reference", "scene.toml"});
    EXPECT_EQ(r.exitStatus, 2) << r.err;
    EXPECT_EQ(r.err, "vtex: error: unknown command 'new line.exr' (vtex --help lists the commands)\n");
}

// Found reading the third fuzz_cli.py campaign's seed and --max-memory findings (a97f912,
// c77d4a0) for the same cause: CLI11 takes -1 for an unsigned option's 2⁶⁴ − 1 and saturates
// larger numbers, so `build --filter-error-samples -1` meant "every node" with exit 0, and its
// range check printed `--max-triangles -1` as "not in range 0.000000 to 1797…" (309 digits).
// A count is a whole number in decimal digits, refused otherwise naming the option.
TEST(Cli, FuzzANegativeOrOverflowingCountIsBadUsage) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "cli_counts";
    fs::create_directories(dir);
    std::ofstream(dir / "plane.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    const std::string obj = (dir / "plane.obj").string(), glb = (dir / "plane.glb").string();
    fs::remove(glb);
    for (const std::string value : {"-1", "18446744073709551616", "0", "1.5"}) {
        const auto r = runVtex({"ingest", obj, "-o", glb, "--max-triangles", value});
        EXPECT_EQ(r.exitStatus, 2) << value << ": " << r.err;
        EXPECT_EQ(r.err.substr(0, r.err.find('\n')),
                  "vtex: error: --max-triangles: must be a whole number from 1 to 18446744073709551615")
            << value;
        EXPECT_FALSE(fs::exists(glb)) << value;
    }
    ASSERT_EQ(runVtex({"ingest", obj, "-o", glb, "--max-triangles", "2"}).exitStatus, 0);
    ASSERT_EQ(runVtex({"sample", glb, "-o", (dir / "p.vtl").string(), "-r", "4"}).exitStatus, 0);
    const auto r = runVtex({"build", (dir / "p.vtl").string(), "-o", (dir / "p.vto").string(),
                            "--filter-error-samples", "-1"});
    EXPECT_EQ(r.exitStatus, 2) << r.err;
    EXPECT_NE(r.err.find("--filter-error-samples: must be a whole number from 0 to 18446744073709551615"),
              std::string::npos)
        << r.err;
}

// `vtex ingest --up/--fit` (issue 16): a Z-up OBJ read as Y-up and fitted into the cell lands in
// the unit cube with its old +Y up, and the report says how; an axis that is not one is bad usage.
TEST(Cli, IngestTurnsAndFitsAsTheFlagsSay) {
    const std::filesystem::path dir = std::filesystem::path(VTEX_TEST_TMP) / "cli_ingest_up";
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "tall.obj") << "v 0 0 0\nv 1 0 0\nv 0 4 0\nf 1 2 3\n";
    const auto r = runVtex({"ingest", (dir / "tall.obj").string(), "-o", (dir / "tall.glb").string(), "--report",
                            (dir / "tall.json").string(), "--up", "y", "--fit", "cell", "-q"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    const std::string report = vtex::test::readText(dir / "tall.json");
    EXPECT_NE(report.find("\"up\": \"y\""), std::string::npos) << report;
    EXPECT_NE(report.find("\"mode\": \"cell\""), std::string::npos) << report;
    EXPECT_NE(report.find("\"scale\": 0.25"), std::string::npos) << report;
    const auto bad = runVtex({"ingest", (dir / "tall.obj").string(), "-o", (dir / "bad.glb").string(), "--up", "w"});
    EXPECT_EQ(bad.exitStatus, 2) << bad.err;
    EXPECT_NE(bad.err.find("--up"), std::string::npos) << bad.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.glb"));
}

// `--threads` has one meaning wherever threads are used (issue 17): the workers a command may
// run at once. Every command that uses threads takes it, and the result does not depend on it: a
// sample and a build with one thread and with two are the same bytes. A negative count is bad
// usage. (That the workers are really held to T is tbb::global_control's job, not checked here.)
TEST(Cli, ThreadsIsTakenEverywhereAndChangesNoByte) {
    const std::filesystem::path dir = std::filesystem::path(VTEX_TEST_TMP) / "cli_threads";
    std::filesystem::create_directories(dir);
    const std::string mesh = (dir / "bush.glb").string();
    ASSERT_EQ(runVtex({"pattern", "bush", "--leaves", "60", "-o", mesh, "-q"}).exitStatus, 0);
    for (const std::string threads : {"1", "2"}) {
        const std::string vtl = (dir / ("b" + threads + ".vtl")).string(), vto = (dir / ("b" + threads + ".vto")).string();
        const auto s = runVtex({"sample", mesh, "-o", vtl, "-r", "32", "--threads", threads, "-q"});
        ASSERT_EQ(s.exitStatus, 0) << s.err;
        const auto b = runVtex({"build", vtl, "-o", vto, "--threads", threads, "-q"});
        ASSERT_EQ(b.exitStatus, 0) << b.err;
    }
    EXPECT_EQ(vtex::test::readText(dir / "b1.vtl"), vtex::test::readText(dir / "b2.vtl"));
    EXPECT_EQ(vtex::test::readText(dir / "b1.vto"), vtex::test::readText(dir / "b2.vto"));
    for (const std::string command : {"sample", "build", "run", "demo"}) {
        const auto r = runVtex({command, "x", "--threads", "-1"});
        EXPECT_EQ(r.exitStatus, 2) << command << ": " << r.err;
        EXPECT_NE(r.err.find("--threads"), std::string::npos) << command << ": " << r.err;
    }
}
