// A vtex built without OpenVDB: `vtex export` refuses a .vdb output with a clear message (bad
// usage, exit 2) before reading anything. Built instead of vdb_export_test.cpp when OpenVDB was
// not found at configure time.
#include "run_vtex.h"

#include <vtex/interop/vdb.h>

#include <gtest/gtest.h>

namespace vtex::interop {
namespace {

static_assert(!kHasOpenVdb);

TEST(VdbExport, ABuildWithoutOpenVdbSaysSo) {
    const auto r = test::runVtex({"export", "missing.vto", "-o", "out.vdb"});
    EXPECT_EQ(r.exitStatus, 2) << r.err;
    EXPECT_NE(r.err.find("built without OpenVDB"), std::string::npos) << r.err;
    EXPECT_EQ(test::lineCount(r.err), 1u) << r.err;
}

}  // namespace
}  // namespace vtex::interop
