// Outputs are regular files or new paths (issue 14, item 2): every command refuses, before any
// work and with exit 3 naming the path, an output that is a directory, a FIFO, a character
// device or the command's own input, and leaves it as it was.
#include "run_vtex.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <cstdlib>
#include <iostream>

#include <sys/stat.h>
#include <sys/sysmacros.h>

using vtex::test::runVtex;
namespace fs = std::filesystem;

namespace {

struct Specials {
    fs::path dir, fifo, device, folder;
    bool haveDevice = false;
};

// A FIFO, a directory and (as root) a character device like /dev/null, made in a fresh folder.
Specials makeSpecials(const std::string& name) {
    Specials s;
    s.dir = fs::path(VTEX_TEST_TMP) / "outputs" / name;
    fs::remove_all(s.dir);
    fs::create_directories(s.dir / "folder");
    s.fifo = s.dir / "fifo";
    s.device = s.dir / "null";
    s.folder = s.dir / "folder";
    EXPECT_EQ(::mkfifo(s.fifo.c_str(), 0600), 0);
    s.haveDevice = ::mknod(s.device.c_str(), S_IFCHR | 0600, makedev(1, 3)) == 0;
    if (!s.haveDevice) std::cout << "no character device: mknod needs root here; that case is skipped\n";
    return s;
}

// Runs `args` with OUT replaced by `target`; expects exit 3 naming it, and `target` unchanged.
void expectRefused(std::vector<std::string> args, const fs::path& target, fs::file_type kind) {
    for (auto& a : args)
        if (a == "OUT") a = target.string();
    const auto r = runVtex(args);
    EXPECT_EQ(r.exitStatus, 3) << args[0] << " → " << target << ": " << r.err;
    EXPECT_NE(r.err.find(target.string()), std::string::npos) << r.err;
    EXPECT_EQ(fs::symlink_status(target).type(), kind) << target << " was replaced";
}

}  // namespace

TEST(Outputs, NoCommandReplacesADeviceAFifoADirectoryOrItsInput) {
    const Specials s = makeSpecials("all");
    const fs::path glb = s.dir / "grass.glb", vtl = s.dir / "grass.vtl", vto = s.dir / "grass.vto";
    ASSERT_EQ(runVtex({"pattern", "grass", "--count", "4", "-o", glb.string()}).exitStatus, 0);
    ASSERT_EQ(runVtex({"sample", glb.string(), "-o", vtl.string(), "-r", "8", "--cyclic"}).exitStatus, 0);
    ASSERT_EQ(runVtex({"build", vtl.string(), "-o", vto.string()}).exitStatus, 0);
    const fs::path scene = s.dir / "scene.toml";
    std::ofstream(s.dir / "plane.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    std::ofstream(scene) << "[camera]\nposition = [0.5, -2, 1.5]\nlook_at = [0.5, 0.5, 0]\nwidth = 8\nheight = 6\n"
                            "[[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\n"
                            "[[surface]]\nmesh = \"plane.obj\"\n";
    const fs::path exr = s.dir / "a.exr";
    ASSERT_EQ(runVtex({"render", scene.string(), "-o", exr.string()}).exitStatus, 0);
    const std::vector<std::vector<std::string>> commands = {
        {"pattern", "grass", "-o", "OUT"},
        {"ingest", glb.string(), "-o", "OUT"},
        {"sample", glb.string(), "-o", "OUT", "-r", "8"},
        {"build", vtl.string(), "-o", "OUT"},
        {"render", scene.string(), "-o", "OUT"},
        {"render", scene.string(), "-o", (s.dir / "b.exr").string(), "--png", "OUT"},
        {"render", scene.string(), "-o", (s.dir / "c.exr").string(), "--stats", "OUT"},
        {"reference", scene.string(), "-o", "OUT"},
        {"compare", exr.string(), exr.string(), "--diff", "OUT"}};
    for (const auto& command : commands) {
        expectRefused(command, s.fifo, fs::file_type::fifo);
        expectRefused(command, s.folder, fs::file_type::directory);
        if (s.haveDevice) expectRefused(command, s.device, fs::file_type::character);
    }
    // The command's own input.
    expectRefused({"ingest", glb.string(), "-o", "OUT"}, glb, fs::file_type::regular);
    expectRefused({"sample", glb.string(), "-o", "OUT", "-r", "8"}, glb, fs::file_type::regular);
    expectRefused({"build", vtl.string(), "-o", "OUT"}, vtl, fs::file_type::regular);
    expectRefused({"render", scene.string(), "-o", "OUT"}, scene, fs::file_type::regular);
    expectRefused({"compare", exr.string(), exr.string(), "--diff", "OUT"}, exr, fs::file_type::regular);
    // Nothing was written beside them (the outputs of the refused renders, temporaries).
    for (const auto& entry : fs::directory_iterator(s.dir)) {
        const std::string name = entry.path().filename().string();
        EXPECT_EQ(name.find(".tmp."), std::string::npos) << name;
        EXPECT_NE(name, "b.exr");
        EXPECT_NE(name, "c.exr");
    }
}

// Inputs are regular files of bounded size (issue 14, item 3): a FIFO hung `vtex run` and
// `vtex compare`, /dev/zero grew a pipeline past 3 GB, a directory ran as an empty pipeline.
TEST(Inputs, AFifoADeviceOrADirectoryIsRefusedAsAnyInput) {
    const Specials s = makeSpecials("inputs");
    std::vector<fs::path> inputs = {s.fifo, s.folder};
    if (s.haveDevice) inputs.push_back(s.device);
    if (fs::exists("/dev/zero")) inputs.push_back("/dev/zero");
    for (const fs::path& input : inputs) {
        const std::string in = input.string(), out = (s.dir / "out.x").string();
        for (const std::vector<std::string>& args : {std::vector<std::string>{"run", in, "-o", (s.dir / "run").string()},
                                                     {"render", in, "-o", out},
                                                     {"reference", in, "-o", out},
                                                     {"compare", in, in},
                                                     {"sample", in, "-o", out},
                                                     {"build", in, "-o", out},
                                                     {"ingest", in, "-o", out}}) {
            const auto r = runVtex(args);
            EXPECT_EQ(r.exitStatus, 3) << args[0] << " " << in << ": " << r.err;
            EXPECT_NE(r.err.find(in), std::string::npos) << r.err;
        }
    }
    EXPECT_FALSE(fs::exists(s.dir / "out.x"));
}

// A command's outputs all or none (issue 14, item 6): when the PNG cannot be written, the EXR
// written before it is not left behind either. The PNG's folder is a file here, which fails
// as root too; where the test may mount a 64 KiB tmpfs, a full disk is tried as well.
TEST(Outputs, ACommandWritesAllItsOutputsOrNone) {
    const Specials s = makeSpecials("all_or_none");
    const fs::path scene = s.dir / "scene.toml";
    std::ofstream(s.dir / "plane.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    std::ofstream(scene) << "[camera]\nposition = [0.5, -2, 1.5]\nlook_at = [0.5, 0.5, 0]\nwidth = 64\nheight = 48\n"
                            "[[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\n"
                            "[[surface]]\nmesh = \"plane.obj\"\n";
    std::ofstream(s.dir / "not-a-folder") << "x";
    const fs::path exr = s.dir / "y.exr";
    const auto r = runVtex({"render", scene.string(), "-o", exr.string(), "--png", (s.dir / "not-a-folder" / "y.png").string(),
                            "--stats", (s.dir / "y.json").string()});
    EXPECT_NE(r.exitStatus, 0);
    EXPECT_FALSE(fs::exists(exr)) << "the EXR was left without its PNG";
    EXPECT_FALSE(fs::exists(s.dir / "y.json"));

    const fs::path small = s.dir / "small";
    fs::create_directories(small);
    if (std::system(("mount -t tmpfs -o size=64k tmpfs " + small.string() + " 2>/dev/null").c_str()) != 0) {
        std::cout << "no full-disk case: cannot mount a tmpfs here\n";
        return;
    }
    // Fill it but for one 4 KiB page: the EXR (under 1 KiB, one page) fits, its PNG then not.
    { std::ofstream(small / "filler", std::ios::binary) << std::string(60 * 1024, 'x'); }
    const auto full = runVtex({"render", scene.string(), "-o", (small / "z.exr").string(), "--png", (small / "z.png").string()});
    const bool both = fs::exists(small / "z.exr") && fs::exists(small / "z.png");
    const bool none = !fs::exists(small / "z.exr") && !fs::exists(small / "z.png");
    std::cout << "full disk: exit " << full.exitStatus << (both ? ", both written" : none ? ", none written" : ", one written")
              << "\n";
    EXPECT_TRUE(full.exitStatus == 0 ? both : none) << full.exitStatus << " " << full.err;
    for (const auto& entry : fs::directory_iterator(small))
        EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
    EXPECT_EQ(std::system(("umount " + small.string()).c_str()), 0);
}

// Found by fuzz_cli.py (fuzz/corpus-cli/regression_3; `vtex inspect`, regression_4, by reading
// for the same call after): a file name too long for the system made std::filesystem's
// throwing calls escape with their own message ("filesystem error: status: File name too long
// [...]"). An output that cannot be created is vtex's failure to write it (exit 1), an input
// that cannot be found is no such file (exit 3).
TEST(Outputs, FuzzANameTooLongGetsVtexsOwnOneLineMessage) {
    const Specials s = makeSpecials("too_long");
    const std::string name = (s.dir / std::string(300, 'a')).string();
    const auto out = runVtex({"pattern", "grass", "--count", "4", "-o", name + ".glb"});
    EXPECT_EQ(out.exitStatus, 1) << out.err;
    EXPECT_EQ(vtex::test::lineCount(out.err), 1u) << out.err;
    EXPECT_NE(out.err.find("cannot create a temporary file beside it: File name too long"), std::string::npos) << out.err;
    const auto in = runVtex({"inspect", name + ".vto"});
    EXPECT_EQ(in.exitStatus, 3) << in.err;
    EXPECT_NE(in.err.find(".vto: no such file"), std::string::npos) << in.err;
    for (const auto& entry : fs::directory_iterator(s.dir))
        EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
}
