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
