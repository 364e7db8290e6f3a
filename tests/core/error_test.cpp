#include <vtex/core/error.h>

#include <gtest/gtest.h>

using vtex::InputError;

TEST(InputError, MessageNamesFileLocationAndProblem) {
    InputError error("scenes/hill.toml", "expected an array of 3 numbers", "camera.position");
    EXPECT_STREQ(error.what(), "scenes/hill.toml: camera.position: expected an array of 3 numbers");
    EXPECT_EQ(error.file(), "scenes/hill.toml");
    EXPECT_EQ(error.location(), "camera.position");
}

TEST(InputError, MessageIsOneLineEvenWhenTheProblemQuotesNewlines) {
    InputError error("a.obj", "bad token 'v 1\n2\r3'");
    EXPECT_EQ(std::string(error.what()).find_first_of("\r\n"), std::string::npos);
}

// A NUL in a path (a scene may name one) cut the message at it (issue 14, item 7); control
// characters are written as \xHH, so the whole message reaches the terminal on one line.
TEST(InputError, AControlCharacterOrNulDoesNotCutTheMessage) {
    const std::string path = std::string("scenes/a") + '\0' + "b.obj";
    InputError error(path, "no such file", "surface[0].mesh");
    const std::string message = error.what();
    EXPECT_EQ(message, "scenes/a\\x00b.obj: surface[0].mesh: no such file");
    EXPECT_EQ(std::string(InputError("x", std::string("bell\a") + "\x1b[31m").what()), "x: bell\\x07\\x1b[31m");
}

TEST(InputError, OneLineIsWhatEveryPrintedMessageGoesThrough) {
    EXPECT_EQ(vtex::oneLine("a\nb\rc\td"), "a b c d");
    EXPECT_EQ(vtex::oneLine(std::string("nul") + '\0' + "\x1b"), "nul\\x00\\x1b");
    EXPECT_EQ(vtex::oneLine("plain: text ☃"), "plain: text ☃");
}
