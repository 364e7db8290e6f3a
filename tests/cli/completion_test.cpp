// `vtex completion bash` and `vtex manpage` (issue 17): generated from the commands' option
// definitions, so checked here against what `vtex CMD --help` prints, an independent reading of
// the same definitions, and by running the completion function in bash.
#include "run_vtex.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using vtex::test::readText;
using vtex::test::runVtex;
using vtex::test::shellQuote;

namespace {

// The commands `vtex --help` lists (its "Subcommands:" block, one per line).
std::vector<std::string> commands() {
    const auto help = runVtex({"--help"}).out;
    std::vector<std::string> out;
    const std::size_t block = help.find("\nSubcommands:");
    if (block == std::string::npos) return out;
    const std::regex line(R"(\n  ([a-z]+)\s)");
    for (auto it = std::sregex_iterator(help.begin() + long(block), help.end(), line);
         it != std::sregex_iterator(); ++it)
        out.push_back((*it)[1]);
    return out;
}

// The long options `vtex CMD --help` prints.
std::set<std::string> longOptions(const std::string& command) {
    const auto help = runVtex({command, "--help"}).out;
    std::set<std::string> out;
    const std::regex option(R"((--[a-z][a-z0-9-]*))");
    for (auto it = std::sregex_iterator(help.begin(), help.end(), option); it != std::sregex_iterator(); ++it)
        out.insert((*it)[1]);
    return out;
}

// What the completion function offers for the words typed so far (the last is being completed).
std::string complete(const fs::path& script, const std::string& words) {
    const fs::path out = fs::path(VTEX_TEST_TMP) / "completion.out";
    const std::string command = "bash -c " + shellQuote("source " + shellQuote(script.string()) + "; COMP_WORDS=(" + words +
                                                        "); COMP_CWORD=$((${#COMP_WORDS[@]} - 1)); _vtex; echo \"${COMPREPLY[*]}\"") +
                                " > " + shellQuote(out.string()) + " 2>&1";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    std::string text = readText(out);
    while (!text.empty() && text.back() == '\n') text.pop_back();
    return text;
}

}  // namespace

TEST(Completion, BashCompletesCommandsTheirOptionsAndTheirChoices) {
    fs::create_directories(VTEX_TEST_TMP);
    const fs::path script = fs::path(VTEX_TEST_TMP) / "vtex.bash";
    ASSERT_EQ(runVtex({"completion", "bash", "-o", script.string()}).exitStatus, 0);
    ASSERT_EQ(std::system(("bash -n " + shellQuote(script.string())).c_str()), 0) << "not valid bash";
    const std::string text = readText(script);
    const auto all = commands();
    ASSERT_GE(all.size(), 10u);
    for (const auto& command : all) {
        // The command's line of options in the script holds every long option of its --help.
        const auto at = text.find("\n        " + command + ")\n            opts='");
        ASSERT_NE(at, std::string::npos) << command;
        const std::string opts = text.substr(at, text.find('\'', text.find('\'', at) + 1) - at);
        for (const auto& option : longOptions(command)) EXPECT_NE(opts.find(" " + option), std::string::npos) << command << " " << option;
    }
    EXPECT_EQ(complete(script, "vtex ren"), "render");
    EXPECT_EQ(complete(script, "vtex render --sha"), "--shadow-refresh --shading");
    EXPECT_EQ(complete(script, "vtex -q render --shading f"), "fast");  // a global flag before the command
    EXPECT_EQ(complete(script, "vtex sample --bounds u"), "unit");
    EXPECT_EQ(runVtex({"completion", "zsh"}).exitStatus, 2);
}

TEST(Completion, TheManualPageListsEveryCommandAndOption) {
    const auto page = runVtex({"manpage"});
    ASSERT_EQ(page.exitStatus, 0) << page.err;
    EXPECT_EQ(page.out.rfind(".TH VTEX 1 ", 0), 0u);
    for (const auto& command : commands()) {
        EXPECT_NE(page.out.find(".SS \"vtex " + command + " "), std::string::npos) << command;
        for (std::string option : longOptions(command)) {
            std::string escaped;  // as troff spells it: every '-' a minus sign
            for (char c : option) escaped += c == '-' ? std::string("\\-") : std::string(1, c);
            EXPECT_NE(page.out.find("\\fB" + escaped + "\\fR"), std::string::npos) << command << " " << option;
        }
    }
    EXPECT_TRUE(std::none_of(page.out.begin(), page.out.end(), [](char c) { return static_cast<unsigned char>(c) >= 0x80; }))
        << "non-ASCII left for troff";
    if (std::system("command -v groff > /dev/null 2>&1") == 0) {
        const fs::path file = fs::path(VTEX_TEST_TMP) / "vtex.1", warnings = fs::path(VTEX_TEST_TMP) / "groff.err";
        ASSERT_EQ(runVtex({"manpage", "-o", file.string()}).exitStatus, 0);
        const std::string command = "groff -man -Tutf8 -ww " + shellQuote(file.string()) + " > /dev/null 2> " + shellQuote(warnings.string());
        EXPECT_EQ(std::system(command.c_str()), 0);
        EXPECT_EQ(readText(warnings), "") << "groff warns";
    }
}
