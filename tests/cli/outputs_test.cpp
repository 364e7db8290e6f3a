// Every input is a regular file of bounded size, and a command writes all its outputs or none.
// Every output against each kind of path it must not write, a full disk among them, is
// output_kinds_test.cpp.
#include "run_vtex.h"

#include <vtex/core/folder_lock.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>

#include <csignal>

#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

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

// An 8×6 render of one lit square: scene.toml and plane.obj in `dir`.
fs::path writePlaneScene(const fs::path& dir) {
    std::ofstream(dir / "plane.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    std::ofstream(dir / "scene.toml") << "[camera]\nposition = [0.5, -2, 1.5]\nlook_at = [0.5, 0.5, 0]\nwidth = 8\nheight = 6\n"
                                         "[[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\n"
                                         "[[surface]]\nmesh = \"plane.obj\"\n";
    return dir / "scene.toml";
}

}  // namespace

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
// written before it is not left behind either. The PNG's folder is a file here, so that its
// temporary cannot even be made (which fails as root too); output_kinds_test.cpp has the PNG
// fail on a full disk instead, once it is written.
TEST(Outputs, ACommandWritesAllItsOutputsOrNone) {
    const Specials s = makeSpecials("all_or_none");
    const fs::path scene = writePlaneScene(s.dir);
    std::ofstream(s.dir / "not-a-folder") << "x";
    const fs::path exr = s.dir / "y.exr";
    const auto r = runVtex({"render", scene.string(), "-o", exr.string(), "--png", (s.dir / "not-a-folder" / "y.png").string(),
                            "--stats", (s.dir / "y.json").string()});
    EXPECT_NE(r.exitStatus, 0);
    EXPECT_FALSE(fs::exists(exr)) << "the EXR was left without its PNG";
    EXPECT_FALSE(fs::exists(s.dir / "y.json"));
}

// `vtex build --source` loads the mesh before the build: a missing or unreadable source fails
// with exit 3 naming it, before the volume is read or built (no "stored nodes" line) and with no
// .vto left, quiet or not. It used to fail only after writing the .vto, and not at all with -q,
// which never loaded the source.
TEST(Outputs, ABadBuildSourceFailsBeforeAnyWorkAndLeavesNoOctree) {
    const Specials s = makeSpecials("build_source");
    const fs::path glb = s.dir / "bush.glb", vtl = s.dir / "bush.vtl", vto = s.dir / "bush.vto";
    ASSERT_EQ(runVtex({"pattern", "bush", "-o", glb.string(), "--leaves", "50"}).exitStatus, 0);
    ASSERT_EQ(runVtex({"sample", glb.string(), "-o", vtl.string(), "-r", "16"}).exitStatus, 0);
    const fs::path missing = s.dir / "missing.glb", garbage = s.dir / "garbage.glb";
    std::ofstream(garbage) << "not a mesh";
    for (const fs::path& bad : {missing, garbage})
        for (const bool quiet : {false, true}) {
            std::vector<std::string> args = {"build", vtl.string(), "-o", vto.string(), "--source", bad.string()};
            if (quiet) args.insert(args.begin(), "-q");
            const auto r = runVtex(args);
            EXPECT_EQ(r.exitStatus, 3) << bad << (quiet ? " -q: " : ": ") << r.err;
            EXPECT_NE(r.err.find(bad.string()), std::string::npos) << r.err;
            EXPECT_EQ(r.err.find("stored nodes"), std::string::npos) << "built before the source was read: " << r.err;
            EXPECT_FALSE(fs::exists(vto)) << bad << (quiet ? " -q" : "");
        }
    // The same build with the real source writes the octree.
    const auto good = runVtex({"build", vtl.string(), "-o", vto.string(), "--source", glb.string()});
    EXPECT_EQ(good.exitStatus, 0) << good.err;
    EXPECT_NE(good.err.find("stored nodes"), std::string::npos) << good.err;
    EXPECT_TRUE(fs::exists(vto));
}

// Two output flags naming one file (`-o a.exr --png a.exr`, written as "./a.exr" too) would
// write both and keep the second: bad usage, refused before any work with both flags named.
TEST(Outputs, TwoOutputFlagsNamingOneFileAreBadUsage) {
    const Specials s = makeSpecials("same_file");
    const fs::path scene = writePlaneScene(s.dir);
    const std::string a = (s.dir / "a.out").string(), again = (s.dir / "." / "a.out").string();
    for (const std::vector<std::string>& args : {std::vector<std::string>{"render", scene.string(), "-o", a, "--png", again},
                                                 {"reference", scene.string(), "-o", a, "--stats", a},
                                                 {"ingest", (s.dir / "plane.obj").string(), "-o", a, "--report", again}}) {
        const auto r = runVtex(args);
        EXPECT_EQ(r.exitStatus, 2) << args[0] << ": " << r.err;
        EXPECT_NE(r.err.find("name the same file"), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(a)) << args[0];
    }
}

// One run per output folder (issue 18; core/folder_lock.h): a second `vtex run` on a folder
// another process holds is refused naming the holder, removes none of its temporaries, and
// runs once the holder is gone (a killed holder's lock is taken over).
TEST(Outputs, ASecondRunOnAFolderInUseIsRefused) {
    const Specials s = makeSpecials("in_use");
    const fs::path pipeline = s.dir / "p.toml", out = s.dir / "out";
    std::ofstream(pipeline) << "[[source]]\nname = \"g\"\npattern = \"grass\"\ncount = 4\n";
    fs::create_directories(out);
    const fs::path theirs = out / ".x.glb.tmp.elsewhere.1.0.0";
    std::ofstream(theirs) << "being written";
    int ready[2];
    ASSERT_EQ(::pipe(ready), 0);
    const pid_t holder = ::fork();
    if (holder == 0) {
        const vtex::FolderLock lock(out);
        (void)!::write(ready[1], "x", 1);
        ::pause();
        ::_exit(0);
    }
    char c = 0;
    ASSERT_EQ(::read(ready[0], &c, 1), 1);
    const auto r = runVtex({"run", pipeline.string(), "-o", out.string()});
    EXPECT_EQ(r.exitStatus, 1) << r.err;
    EXPECT_NE(r.err.find("in use by"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(std::to_string(holder)), std::string::npos) << r.err;
    EXPECT_TRUE(fs::exists(theirs)) << "a refused run removed the holder's temporary";
    ::kill(holder, SIGKILL);
    ::waitpid(holder, nullptr, 0);
    const auto after = runVtex({"run", pipeline.string(), "-o", out.string()});
    EXPECT_EQ(after.exitStatus, 0) << after.err;
    EXPECT_FALSE(fs::exists(theirs)) << "the run that holds the lock clears a dead writer's temporaries";
}

// Found by fuzz_cli.py (fuzz/corpus-cli/regression_3, regression_9; `vtex inspect`,
// regression_4, by reading for the same call after): a file name too long or a link loop made
// std::filesystem's throwing calls escape with their own message ("filesystem error: status:
// File name too long [...]"). An output that cannot be created is vtex's failure to write it
// (exit 1), an input that cannot be found is no such file (exit 3).
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
    // A link loop in the way (regression_9): no such folder, in vtex's words.
    fs::create_symlink("loop-b", s.dir / "loop-a");
    fs::create_symlink("loop-a", s.dir / "loop-b");
    const auto loop = runVtex({"pattern", "grass", "--count", "4", "-o", (s.dir / "loop-a" / "x.glb").string()});
    EXPECT_EQ(loop.exitStatus, 1) << loop.err;
    EXPECT_NE(loop.err.find("x.glb: output directory does not exist"), std::string::npos) << loop.err;
    for (const auto& entry : fs::directory_iterator(s.dir))
        EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
}

// An image's format follows its name (issue 17): `-o x.png` writes a PNG and `-o x.exr` an EXR,
// for both renderers; another extension, or `--png` naming a non-PNG, is bad usage before any
// rendering, and nothing is written. `vtex compare` reads either: an EXR against its own 8-bit
// sRGB PNG differs by the PNG's rounding alone, at most half a step of 8 bits at the sRGB curve's
// steepest on [0, 1] (2.4/1.055 × ((1 + 0.055)/1.055)^1.4 = 2.275, times 0.5/255: 0.0045).
TEST(Outputs, AnImageFormatFollowsItsNameAndCompareReadsBoth) {
    const Specials s = makeSpecials("image_formats");
    const fs::path scene = writePlaneScene(s.dir);
    const auto magic = [](const fs::path& file) { return vtex::test::readText(file).substr(0, 4); };
    for (const std::string command : {"render", "reference"}) {
        const fs::path exr = s.dir / (command + ".exr"), png = s.dir / (command + ".PNG");
        ASSERT_EQ(runVtex({command, scene.string(), "-o", exr.string(), "-q"}).exitStatus, 0);
        ASSERT_EQ(runVtex({command, scene.string(), "-o", png.string(), "-q"}).exitStatus, 0);
        EXPECT_EQ(magic(exr), std::string("\x76\x2f\x31\x01", 4)) << command;  // OpenEXR
        EXPECT_EQ(magic(png), "\x89PNG") << command;
        const auto c = runVtex({"compare", exr.string(), png.string(), "--json"});
        ASSERT_EQ(c.exitStatus, 0) << c.err;
        const double worst = std::stod(c.out.substr(c.out.find("\"error\":") + 8));
        EXPECT_LE(worst, 0.0045) << c.out;
        EXPECT_EQ(runVtex({"compare", png.string(), png.string()}).exitStatus, 0);
        for (const std::vector<std::string>& bad : {std::vector<std::string>{"-o", (s.dir / "x.tif").string()},
                                                    {"-o", (s.dir / "x.exr").string(), "--png", (s.dir / "y.exr").string()}}) {
            std::vector<std::string> args{command, scene.string()};
            args.insert(args.end(), bad.begin(), bad.end());
            const auto r = runVtex(args);
            EXPECT_EQ(r.exitStatus, 2) << command << ": " << r.err;
            EXPECT_NE(r.err.find("unknown image format"), std::string::npos) << r.err;
            EXPECT_FALSE(fs::exists(s.dir / "x.tif") || fs::exists(s.dir / "x.exr") || fs::exists(s.dir / "y.exr"));
        }
    }
}

// Found by fuzz_cli.py (third campaign, fuzz/corpus-cli/regression_16, a timeout): `vtex sample
// hill.obj -r 4096 -o missing/x.vtl` sampled for 20 s and more before finding, on writing, that
// the output's folder does not exist (exit 1). A new path in a missing folder (or behind a file
// or a link loop) is refused before any work: here before the memory estimate that would refuse
// the work itself (exit 3), which came first.
TEST(Outputs, FuzzAnOutputInAMissingFolderIsRefusedBeforeAnyWork) {
    const Specials s = makeSpecials("missing_folder");
    const fs::path scene = writePlaneScene(s.dir);
    std::ofstream(s.dir / "not-a-folder") << "x";
    for (const std::string folder : {"missing", "not-a-folder"}) {
        const std::string out = (s.dir / folder / "x.out").string();
        for (const std::vector<std::string>& args :
             {std::vector<std::string>{"sample", (s.dir / "plane.obj").string(), "-o", out, "-r", "1048576"},
              {"render", scene.string(), "-o", out, "--width", "16384", "--height", "16384", "--max-memory", "1MiB"},
              {"pattern", "brushed", "-o", out, "--count", "10000000"}}) {
            const auto r = runVtex(args);
            EXPECT_EQ(r.exitStatus, 1) << args[0] << ": " << r.err;
            EXPECT_EQ(r.err, "vtex: error: " + out + ": output directory does not exist\n") << args[0];
        }
    }
    EXPECT_FALSE(fs::exists(s.dir / "missing"));
}
