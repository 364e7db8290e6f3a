/// @file
/// @brief Output files that appear whole or not at all.
///
/// Every artifact vtex writes goes through AtomicOutputFile: the bytes go to a uniquely named
/// temporary beside the target (same directory, so the final rename never crosses a file
/// system), which is flushed to disk and renamed over the target by commit(). A writer that
/// throws, or a process killed mid-write, leaves the target untouched; the destructor removes
/// an uncommitted temporary.
#pragma once

#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string_view>
#include <vector>

namespace vtex {

class AtomicOutputFile {
public:
    /// Creates the temporary now, so an unwritable destination fails before any work.
    /// Throws IoError.
    explicit AtomicOutputFile(std::filesystem::path target);
    ~AtomicOutputFile();

    AtomicOutputFile(const AtomicOutputFile&) = delete;
    AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

    /// A binary stream on the temporary, for writers that take a std::ostream.
    std::ostream& stream();

    /// The temporary's path, for a library that insists on opening a file name itself. Do not
    /// mix with stream(), and prefer stream(): finish() cannot see such a library's write errors
    /// (OpenEXR's, for one, were lost when its stream closed: the EXR writer uses stream()).
    const std::filesystem::path& temporaryPath() const { return mTemporary; }
    const std::filesystem::path& target() const { return mTarget; }

    /// Flushes the temporary to disk (a full disk shows here); nothing is renamed yet. Throws
    /// IoError. Idempotent.
    void finish();

    /// finish(), then renames the temporary over the target. Throws IoError.
    void commit();

private:
    std::filesystem::path mTarget;
    std::filesystem::path mTemporary;
    std::ofstream mStream;
    bool mCommitted = false;
    bool mFinished = false;
};

/// A command's outputs all or none: finishes every file (so that a full disk or a failed write
/// fails before any target is replaced), then renames them one after the other. Only a rename
/// failing between two others (the directory removed meanwhile) can leave some in place.
void commitAll(std::initializer_list<AtomicOutputFile*> files);

/// Refuses (vtex::InputError naming `target`) an output path that exists and is not a regular
/// file once links are followed — a directory, a FIFO, a device, a socket: the rename of an
/// atomic output would replace it (as root, `-o /dev/null` would destroy /dev/null) — or that
/// is the same file as one of `inputs` (`-o scene.toml` would replace the scene), a link to it
/// included. A new path whose folder does not exist is refused too (vtex::IoError, "output
/// directory does not exist"). A command calls it for each of its outputs, with every file it
/// reads, before any work; AtomicOutputFile calls it again when created.
///
/// A symbolic link to an unrelated regular file is an ordinary output, and the output replaces
/// the link itself (rename(2) replaces the name it is given, as `mv` does): the file the link
/// pointed to is left as it was, and the temporary is made beside the link, in the folder the
/// user named, not in the link target's.
void checkOutputPath(const std::filesystem::path& target, const std::vector<std::filesystem::path>& inputs = {});

/// The same for an output folder (`vtex run -o DIR`, `vtex demo -o DIR`): refuses one that
/// exists and is not a directory once links are followed — a regular file, a FIFO, a device —
/// or that is one of `inputs`, before anything is made in it.
void checkOutputFolder(const std::filesystem::path& folder, const std::vector<std::filesystem::path>& inputs = {});

/// Writes `bytes` to `target` atomically. Throws IoError.
void writeFileAtomically(const std::filesystem::path& target, std::string_view bytes);

}  // namespace vtex
