/// @file
/// @brief A scratch folder of the running test's own.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace vtex::test {

/// VTEX_TEST_TMP/<group>/<Suite>.<Test>, created. ctest runs every test of a file as its own
/// process, in parallel: tests that write the same file name into one shared folder race
/// (one truncates `ground.obj` while another's `vtex` reads it), so each writes into its own.
inline std::filesystem::path scratchDir(const std::string& group) {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "no_test";
    for (char& c : name)
        if (c == '/') c = '_';  // parameterised tests' names hold '/'
    const std::filesystem::path dir = std::filesystem::path(VTEX_TEST_TMP) / group / name;
    std::filesystem::create_directories(dir);
    return dir;
}

}  // namespace vtex::test
