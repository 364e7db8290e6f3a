// The command-line contract of DESIGN.md: --help and --version succeed on stdout, bad usage
// exits 2 with a one-line error on stderr, and no invocation dies of a signal.
#include "run_vtex.h"

#include <vtex/core/version.h>

#include <gtest/gtest.h>

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
