#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>

#include <gtest/gtest.h>

#include <fstream>

#include <sys/stat.h>
#include <sstream>

namespace fs = std::filesystem;

namespace {

fs::path freshDirectory(const std::string& name) {
    fs::path dir = fs::path(VTEX_TEST_TMP) / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string readAll(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
}

std::size_t entryCount(const fs::path& dir) {
    return std::distance(fs::directory_iterator(dir), fs::directory_iterator());
}

}  // namespace

TEST(AtomicOutputFile, CommitPutsTheWholeFileInPlaceAndLeavesNoTemporary) {
    const fs::path dir = freshDirectory("commit");
    vtex::writeFileAtomically(dir / "out.bin", std::string("hello\0world", 11));
    EXPECT_EQ(readAll(dir / "out.bin"), std::string("hello\0world", 11));
    EXPECT_EQ(entryCount(dir), 1u);
}

TEST(AtomicOutputFile, AWriterThatThrowsLeavesTheOldTargetUntouched) {
    const fs::path dir = freshDirectory("abandon");
    vtex::writeFileAtomically(dir / "out.txt", "old");
    try {
        vtex::AtomicOutputFile file(dir / "out.txt");
        file.stream() << "half of the new conte";
        throw std::runtime_error("writer failed");
    } catch (const std::runtime_error&) {
    }
    EXPECT_EQ(readAll(dir / "out.txt"), "old");
    EXPECT_EQ(entryCount(dir), 1u) << "the temporary was not removed";
}

TEST(AtomicOutputFile, TheTargetDoesNotExistUntilCommit) {
    const fs::path dir = freshDirectory("pending");
    vtex::AtomicOutputFile file(dir / "out.txt");
    file.stream() << "data";
    file.stream().flush();
    EXPECT_FALSE(fs::exists(dir / "out.txt"));
    EXPECT_EQ(file.temporaryPath().parent_path(), dir) << "temporary must be beside the target";
    file.commit();
    EXPECT_EQ(readAll(dir / "out.txt"), "data");
}

TEST(AtomicOutputFile, ALibraryCanWriteThroughTheTemporaryPath) {
    const fs::path dir = freshDirectory("by_name");
    vtex::AtomicOutputFile file(dir / "image.exr");
    std::ofstream(file.temporaryPath()) << "pixels";
    file.commit();
    EXPECT_EQ(readAll(dir / "image.exr"), "pixels");
}

TEST(AtomicOutputFile, AMissingDirectoryIsRefusedBeforeAnyWork) {
    const fs::path dir = freshDirectory("missing");
    EXPECT_THROW(vtex::AtomicOutputFile{dir / "no" / "such" / "dir" / "out.txt"}, vtex::IoError);
    EXPECT_THROW(vtex::AtomicOutputFile{dir}, vtex::IoError);
}

TEST(AtomicOutputFile, TheFileGetsTheUsersUmaskNotPrivateMode) {
    const fs::path dir = freshDirectory("mode");
    const mode_t previous = ::umask(022);
    vtex::writeFileAtomically(dir / "out.txt", "shared");
    ::umask(previous);
    const auto permissions = fs::status(dir / "out.txt").permissions();
    EXPECT_EQ(permissions, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                               fs::perms::others_read);
}

// An output folder is a directory (a link to one is that directory) or a new path; a file, a
// FIFO or the command's own input in its place is bad input, not an I/O failure.
TEST(CheckOutputFolder, ADirectoryALinkToOneOrANewPathIsAcceptedAnythingElseRefused) {
    const fs::path dir = freshDirectory("output_folder");
    fs::create_directories(dir / "folder");
    fs::create_directory_symlink(dir / "folder", dir / "link");
    std::ofstream(dir / "pipeline.toml") << "x";
    ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
    EXPECT_NO_THROW(vtex::checkOutputFolder(dir / "folder", {dir / "pipeline.toml"}));
    EXPECT_NO_THROW(vtex::checkOutputFolder(dir / "link", {dir / "pipeline.toml"}));
    EXPECT_NO_THROW(vtex::checkOutputFolder(dir / "new", {dir / "pipeline.toml"}));
    EXPECT_THROW(vtex::checkOutputFolder(dir / "fifo"), vtex::InputError);
    EXPECT_THROW(vtex::checkOutputFolder(dir / "pipeline.toml"), vtex::InputError);
    try {
        vtex::checkOutputFolder(dir / "pipeline.toml", {dir / "pipeline.toml"});
        ADD_FAILURE() << "the pipeline file was accepted as its own output folder";
    } catch (const vtex::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("own input"), std::string::npos) << e.what();
    }
}
