// Every output of every subcommand set to each kind of path it must not write (issue 14): a
// directory, a FIFO, a character device, a symbolic link to one of the command's own inputs
// (for an output folder: a FIFO, a device, a regular file, a link to its input) and a full
// file system. A refused kind exits 3 naming the path before any work; a full disk exits
// non-zero with one `vtex: error:` line naming the file. Either way the folder the command
// ran in is as it was, entry for entry and byte for byte: no temporary, no partial output, no
// companion output (the EXR of a refused PNG), the special file still what it was, the link
// still a link and its input unchanged. A link to an unrelated file is an ordinary output.
#include "run_vtex.h"

#include <gtest/gtest.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>

using vtex::test::lineCount;
using vtex::test::readText;
using vtex::test::runVtex;
namespace fs = std::filesystem;

namespace {

// One output of one subcommand; "OUT" in `args` stands for the path under test.
struct Output {
    std::string name;              // "render --png", for messages
    std::vector<std::string> args;
    std::vector<fs::path> inputs;  // every file the command reads: a link to each is tried
    bool folder = false;           // an output folder (run, demo) rather than a file
};

// What a command may not write in place of an output, and the path standing for it.
struct Target {
    std::string kind;
    fs::path path;
};

// Subcommands with nothing to write but stdout; every other one has its rows in the table.
const std::set<std::string> kWritesNoFile = {"inspect"};

// in/ holds the inputs, t/ the paths put in place of an output, out/ the companion outputs of a
// case (the EXR beside the PNG under test). All three are compared before and after each case.
struct Workspace {
    fs::path in, t, out;
    bool haveDevice = false;
};

void writeText(const fs::path& file, const std::string& text) { std::ofstream(file, std::ios::binary) << text; }

// One entry of a folder, links not followed: its type, and a link's target or a file's bytes.
struct Entry {
    fs::file_type type = fs::file_type::none;
    std::string content;
    bool operator==(const Entry&) const = default;
};
using Snapshot = std::map<std::string, Entry>;

Snapshot snapshot(const fs::path& root) {
    Snapshot entries;
    for (const auto& item : fs::recursive_directory_iterator(root)) {
        Entry entry{fs::symlink_status(item.path()).type(), {}};
        if (entry.type == fs::file_type::symlink) entry.content = fs::read_symlink(item.path()).string();
        if (entry.type == fs::file_type::regular) entry.content = readText(item.path());
        entries[item.path().lexically_relative(root).string()] = entry;  // not fs::relative: it follows links
    }
    return entries;
}

// The entries that appeared, went or changed, one a line; empty when none did.
std::string changes(const Snapshot& before, const Snapshot& after) {
    std::string text;
    for (const auto& [name, entry] : after)
        if (!before.count(name)) text += "  left: " + name + "\n";
        else if (!(before.at(name) == entry)) text += "  changed: " + name + "\n";
    for (const auto& [name, entry] : before)
        if (!after.count(name)) text += "  gone: " + name + "\n";
    return text;
}

// Puts `root` back as `before` had it, so that a case that replaced a link or left a file
// does not make the cases after it test something else.
void restore(const fs::path& root, const Snapshot& before) {
    const Snapshot now = snapshot(root);
    std::error_code ignored;
    for (const auto& [name, entry] : now)
        if (!before.count(name)) fs::remove_all(root / name, ignored);
    for (const auto& [name, entry] : before) {
        if (now.count(name) && now.at(name) == entry) continue;
        const fs::path path = root / name;
        fs::remove_all(path, ignored);
        switch (entry.type) {
        case fs::file_type::directory: fs::create_directories(path); break;
        case fs::file_type::symlink: fs::create_symlink(entry.content, path); break;
        case fs::file_type::fifo: ::mkfifo(path.c_str(), 0600); break;
        case fs::file_type::character: ::mknod(path.c_str(), S_IFCHR | 0600, makedev(1, 3)); break;
        default: std::ofstream(path, std::ios::binary) << entry.content;
        }
    }
}

// The inputs, made by vtex itself so that they are what a user would hand it: a grass mesh, its
// sampled volume and octree, a scene using them over a plane, two images, a pipeline.
Workspace makeWorkspace(const std::string& name) {
    const fs::path root = fs::path(VTEX_TEST_TMP) / "output_kinds" / name / "ws";
    fs::remove_all(root);
    Workspace w{root / "in", root / "t", root / "out"};
    for (const fs::path& dir : {w.in, w.t, w.out}) fs::create_directories(dir);
    const std::string glb = (w.in / "grass.glb").string(), vtl = (w.in / "grass.vtl").string();
    EXPECT_EQ(runVtex({"-q", "pattern", "grass", "--count", "4", "-o", glb}).exitStatus, 0);
    EXPECT_EQ(runVtex({"-q", "sample", glb, "-o", vtl, "-r", "8", "--cyclic"}).exitStatus, 0);
    EXPECT_EQ(runVtex({"-q", "build", vtl, "-o", (w.in / "grass.vto").string()}).exitStatus, 0);
    writeText(w.in / "plane.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    writeText(w.in / "scene.toml",
              "[camera]\nposition = [0.5, -2, 1.5]\nlook_at = [0.5, 0.5, 0]\nwidth = 8\nheight = 6\n"
              "[[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\n"
              "[[texel]]\nname = \"grass\"\nvolume = \"grass.vto\"\nsource = \"grass.glb\"\n"
              "[[surface]]\nmesh = \"plane.obj\"\ntexel = \"grass\"\nheight = 0.2\n");
    EXPECT_EQ(runVtex({"-q", "render", (w.in / "scene.toml").string(), "-o", (w.in / "a.exr").string()}).exitStatus, 0);
    fs::copy_file(w.in / "a.exr", w.in / "b.exr");
    writeText(w.in / "pipeline.toml", "[[source]]\nname = \"grass\"\npattern = \"grass\"\ncount = 4\n");

    fs::create_directories(w.t / "dir");
    EXPECT_EQ(::mkfifo((w.t / "fifo").c_str(), 0600), 0);
    w.haveDevice = ::mknod((w.t / "null").c_str(), S_IFCHR | 0600, makedev(1, 3)) == 0;
    if (!w.haveDevice)
        std::cout << "character device cases skipped: mknod: " << std::strerror(errno) << " (it needs root)\n";
    writeText(w.t / "file", "a regular file\n");
    writeText(w.t / "unrelated", "an unrelated file\n");
    for (const auto& entry : fs::directory_iterator(w.in))
        fs::create_symlink(entry.path(), w.t / ("to-" + entry.path().filename().string()));
    return w;
}

std::vector<Output> outputTable(const Workspace& w) {
    const std::string glb = (w.in / "grass.glb").string(), vtl = (w.in / "grass.vtl").string();
    const std::string a = (w.in / "a.exr").string(), b = (w.in / "b.exr").string();
    const std::string scene = (w.in / "scene.toml").string(), pipeline = (w.in / "pipeline.toml").string();
    const std::vector<fs::path> sceneFiles = {scene, w.in / "plane.obj", w.in / "grass.vto", glb};
    std::vector<Output> table = {
        {"pattern -o", {"pattern", "grass", "--count", "4", "-o", "OUT"}, {}},
        {"ingest -o", {"ingest", glb, "-o", "OUT"}, {glb}},
        {"ingest --report", {"ingest", glb, "-o", (w.out / "m.glb").string(), "--report", "OUT"}, {glb}},
        {"sample -o", {"sample", glb, "-o", "OUT", "-r", "8", "--cyclic"}, {glb}},
        {"build -o", {"build", vtl, "-o", "OUT"}, {vtl}},
        {"export -o", {"export", (w.in / "grass.vto").string(), "-o", "OUT"}, {w.in / "grass.vto"}},
        {"export -o (layout)", {"export", scene, "-o", "OUT"}, sceneFiles},
        {"compare --diff", {"compare", a, b, "--diff", "OUT"}, {a, b}},
        {"run -o", {"run", pipeline, "-o", "OUT"}, {pipeline}, true},
        {"demo -o", {"demo", "-o", "OUT", "--resolution", "4", "--scale", "0.05"}, {}, true},
        {"completion -o", {"completion", "bash", "-o", "OUT"}, {}},
        {"manpage -o", {"manpage", "-o", "OUT"}, {}},
    };
    const std::string companion = (w.out / "c.exr").string();
    for (const std::string command : {"render", "reference"}) {
        table.push_back({command + " -o", {command, scene, "-o", "OUT"}, sceneFiles});
        table.push_back({command + " --png", {command, scene, "-o", companion, "--png", "OUT"}, sceneFiles});
        table.push_back({command + " --stats", {command, scene, "-o", companion, "--stats", "OUT"}, sceneFiles});
    }
    return table;
}

// The kinds `output` must refuse: for a file, a directory, a FIFO, a device and a link to each
// input; for a folder, a FIFO, a device, a regular file and a link to each input.
std::vector<Target> refusedTargets(const Workspace& w, const Output& output) {
    std::vector<Target> targets = {{"a FIFO", w.t / "fifo"}};
    if (w.haveDevice) targets.push_back({"a character device", w.t / "null"});
    targets.push_back(output.folder ? Target{"a regular file", w.t / "file"} : Target{"a directory", w.t / "dir"});
    for (const fs::path& input : output.inputs) {
        const std::string name = input.filename().string();
        targets.push_back({"a link to its input " + name, w.t / ("to-" + name)});
    }
    return targets;
}

vtex::test::RunResult runWith(const Output& output, const fs::path& target) {
    std::vector<std::string> args = {"-q"};  // stderr then carries the error alone
    for (const std::string& arg : output.args) args.push_back(arg == "OUT" ? target.string() : arg);
    return runVtex(args);
}

// One line, `vtex: error: ` and the path.
bool isOneErrorLineNaming(const std::string& err, const fs::path& path) {
    return lineCount(err) == 1 && err.rfind("vtex: error: ", 0) == 0 && err.find(path.string()) != std::string::npos;
}

// A small tmpfs, unmounted however the test ends.
struct SmallFileSystem {
    fs::path mountPoint;
    bool mounted = false;
    std::string reason;
    explicit SmallFileSystem(const fs::path& where) : mountPoint(where) {
        fs::create_directories(where);
        mounted = ::mount("tmpfs", where.c_str(), "tmpfs", 0, "size=64k") == 0;
        if (!mounted) reason = std::string("mount -t tmpfs: ") + std::strerror(errno);
    }
    ~SmallFileSystem() {
        if (mounted && ::umount2(mountPoint.c_str(), MNT_DETACH) != 0)
            ADD_FAILURE() << "cannot unmount " << mountPoint << ": " << std::strerror(errno);
    }
};

// Writes pages until the file system refuses one: then not a byte of any output fits.
void fill(const fs::path& file) {
    std::ofstream filler(file, std::ios::binary);
    const std::string page(4096, 'x');
    while (filler.write(page.data(), std::streamsize(page.size())) && filler.flush()) {}
}

// The options `help` lists whose description says they write something ("Mesh to write",
// "Write a JSON report", "Output directory"), each as its names ("-o,--output").
std::vector<std::string> writingOptions(const std::string& help) {
    std::vector<std::string> options;
    std::istringstream lines(help);
    std::string line, names, described;
    auto finish = [&] {
        std::string lower = described;
        for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
        const bool writes = lower.find("write") != std::string::npos || lower.find("directory") != std::string::npos;
        if (!names.empty() && writes)
            options.push_back(names);
        names.clear();
        described.clear();
    };
    while (std::getline(lines, line)) {
        const std::size_t first = line.find_first_not_of(' ');
        if (first == std::string::npos) continue;
        if (first == 0 || (first == 2 && line[2] == '-')) finish();  // a heading, or the next option
        if (first == 2 && line[2] == '-') names = line.substr(2, line.find(' ', 2) - 2);
        described += line + " ";  // an option's description may wrap to the next line
    }
    finish();
    return options;
}

}  // namespace

// The table is the whole command line: a subcommand `vtex --help` lists, or an option that says
// it writes something, without its row would go untested, so it fails here until it gets one
// (or the subcommand joins kWritesNoFile).
TEST(OutputKinds, EverySubcommandAndEveryOutputOptionIsInTheTable) {
    const Workspace w = makeWorkspace("coverage");
    std::set<std::string> commands = kWritesNoFile, options;
    for (const Output& output : outputTable(w)) {
        commands.insert(output.args[0]);
        for (std::size_t i = 1; i < output.args.size(); ++i)
            if (output.args[i] == "OUT") options.insert(output.args[0] + " " + output.args[i - 1]);
    }
    const auto help = runVtex({"--help"});
    ASSERT_EQ(help.exitStatus, 0);
    const std::size_t list = help.out.find("Subcommands:");
    ASSERT_NE(list, std::string::npos) << help.out;
    std::istringstream lines(help.out.substr(list));
    std::string line, name;
    std::getline(lines, line);
    int listed = 0;
    while (std::getline(lines, line) && std::istringstream(line) >> name) {
        ++listed;
        EXPECT_TRUE(commands.count(name)) << "vtex " << name << " has no row in the output table";
        int found = 0;
        for (const std::string& names : writingOptions(runVtex({name, "--help"}).out)) {
            std::istringstream each(names);
            bool covered = false;
            for (std::string option; std::getline(each, option, ',');)
                covered |= options.count(name + " " + option) > 0;
            EXPECT_TRUE(covered) << "vtex " << name << " " << names << " writes something and has no row";
            ++found;
        }
        EXPECT_EQ(found == 0, kWritesNoFile.count(name) > 0) << "vtex " << name;
    }
    EXPECT_EQ(listed, int(commands.size())) << help.out;
}

TEST(OutputKinds, EveryRefusedKindExits3NamingItAndLeavesEverythingAsItWas) {
    const Workspace w = makeWorkspace("refused");
    const fs::path root = w.in.parent_path();
    for (const Output& output : outputTable(w))
        for (const Target& target : refusedTargets(w, output)) {
            const auto before = snapshot(root);
            const auto r = runWith(output, target.path);
            const std::string what = output.name + " to " + target.kind;
            EXPECT_EQ(r.exitStatus, 3) << what << ": " << r.err;
            EXPECT_TRUE(isOneErrorLineNaming(r.err, target.path)) << what << ": " << r.err;
            EXPECT_EQ(changes(before, snapshot(root)), "") << what;
            restore(root, before);
        }
}

// A link to an unrelated regular file is an ordinary output: the rename that puts the output in
// place replaces the link itself, and the file it pointed to is left as it was (atomic_file.h).
TEST(OutputKinds, ALinkToAnUnrelatedFileIsReplacedByTheOutput) {
    const Workspace w = makeWorkspace("unrelated_link");
    const fs::path root = w.in.parent_path(), link = w.t / "link";
    fs::create_symlink(w.t / "unrelated", link);
    const auto before = snapshot(root);
    for (const Output& output : outputTable(w)) {
        if (output.folder) continue;  // a link to a folder is that folder: the ordinary case
        const auto r = runWith(output, link);
        EXPECT_EQ(r.exitStatus, 0) << output.name << ": " << r.err;
        EXPECT_EQ(fs::symlink_status(link).type(), fs::file_type::regular) << output.name;
        EXPECT_GT(fs::file_size(link), 0u) << output.name;
        // The link back and the companions gone, the folder must be as it was: t/unrelated
        // unchanged, nothing left.
        fs::remove(link);
        fs::create_symlink(w.t / "unrelated", link);
        for (const auto& entry : fs::directory_iterator(w.out)) fs::remove(entry.path());
        EXPECT_EQ(changes(before, snapshot(root)), "") << output.name;
        restore(root, before);
    }
}

// The output on a full file system, everything else (inputs, companion outputs) beside it on
// the test's own: the command fails naming the file, and neither file system keeps anything of
// it. A pipeline's output folder is made before any stage runs, so its subfolders stay (empty).
TEST(OutputKinds, AFullFileSystemFailsWithOneLineNamingTheFileAndLeavesNothing) {
    const Workspace w = makeWorkspace("full");
    const SmallFileSystem small(w.in.parent_path().parent_path() / "full");
    if (!small.mounted) {
        std::cout << "full file system cases skipped: " << small.reason << "\n";
        GTEST_SKIP() << small.reason;
    }
    fill(small.mountPoint / "filler");
    const fs::path root = w.in.parent_path();
    for (const Output& output : outputTable(w)) {
        const fs::path target = small.mountPoint / "output";
        const auto before = snapshot(root);
        const auto r = runWith(output, target);
        EXPECT_NE(r.exitStatus, 0) << output.name;
        EXPECT_EQ(r.signal, 0) << output.name;
        EXPECT_TRUE(isOneErrorLineNaming(r.err, target)) << output.name << ": " << r.err;
        EXPECT_EQ(changes(before, snapshot(root)), "") << output.name;
        restore(root, before);
        if (output.folder && fs::is_directory(target)) {
            // Empty subfolders and the folder's lock file (folder_lock.h: it stays by design).
            for (const auto& entry : fs::recursive_directory_iterator(target))
                EXPECT_TRUE(entry.is_directory() || entry.path().filename() == ".vtex.lock")
                    << output.name << " left " << entry.path();
            fs::remove_all(target);
        }
        std::set<std::string> left;
        for (const auto& entry : fs::directory_iterator(small.mountPoint))
            left.insert(entry.path().filename().string());
        EXPECT_EQ(left, std::set<std::string>{"filler"}) << output.name;
        for (const std::string& name : left)
            if (name != "filler") fs::remove_all(small.mountPoint / name);
    }
}
