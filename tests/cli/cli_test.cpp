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
