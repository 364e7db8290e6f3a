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
