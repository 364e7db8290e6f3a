// openVto: a .vto read a level at a time. The same tree as readVto's, bytes read that add up
// section by section, a damaged level refused only when it is used, concurrent first uses.
#include "random_volume.h"

#include <vtex/core/error.h>
#include <vtex/octree/octree.h>

#include "../../octree/src/container.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

namespace vtex::octree {
namespace {

namespace fs = std::filesystem;

// A volume of 2^6 voxels a side with voxels scattered over it: every level holds nodes.
Octree scatteredOctree(unsigned seed) {
    NullProgress progress;
    return buildOctree(test::randomVolume(6, 3000, seed), {}, progress);
}

fs::path writeTree(const Octree& tree, const std::string& name) {
    const fs::path path = fs::path(VTEX_TEST_TMP) / "lazy" / name;
    fs::create_directories(path.parent_path());
    writeVto(tree, path);
    return path;
}

std::string readBytes(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

void writeBytes(const fs::path& file, const std::string& bytes) {
    std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

// The section table of a container, parsed independently of the reader under test.
std::vector<detail::TableEntry> sectionTable(const std::string& bytes) {
    detail::ByteReader head(std::string_view(bytes).substr(12, 4));
    const std::uint32_t count = head.u32();
    std::vector<detail::TableEntry> entries;
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::size_t at = detail::kHeaderSize + detail::kTableEntrySize * i;
        detail::ByteReader r(std::string_view(bytes).substr(at + 8, 24));
        detail::TableEntry e{bytes.substr(at, 4), 0, 0, 0};
        e.offset = r.u64();
        e.size = r.u64();
        e.sum = r.u64();
        entries.push_back(e);
    }
    return entries;
}

detail::TableEntry entryOf(const std::vector<detail::TableEntry>& table, const std::string& tag) {
    for (const auto& e : table)
        if (e.tag == tag) return e;
    throw std::runtime_error("no section " + tag);
}

TEST(LazyVto, ReadsTheHeaderAtOpenAndEachLevelOnFirstUseAndEndsWithTheSameTreeAsReadVto) {
    const Octree built = scatteredOctree(3);
    const fs::path path = writeTree(built, "same.vto");
    const std::string bytes = readBytes(path);
    const auto table = sectionTable(bytes);
    const auto lazy = openVto(path);
    // At open: the header and table, HEAD, STAT and PROF (the density profile's layer means,
    // which the build stores), nothing of the levels.
    std::uint64_t expected = detail::kHeaderSize + detail::kTableEntrySize * table.size() + entryOf(table, "HEAD").size +
                             entryOf(table, "STAT").size + entryOf(table, "PROF").size;
    EXPECT_EQ(lazy->bytesRead(), expected);
    EXPECT_EQ(lazy->info, built.info);
    EXPECT_EQ(lazy->stats, built.stats);
    ASSERT_TRUE(lazy->layerMeans);
    EXPECT_EQ(*lazy->layerMeans, *built.layerMeans);
    ASSERT_EQ(lazy->levelCount(), built.levelCount());
    for (const auto& level : lazy->levels) EXPECT_TRUE(level.empty());
    // Level 3 brings levels 0 … 3, each section's payload counted once; asking again reads nothing.
    lazy->loadLevels(3);
    for (const char* tag : {"LV00", "LV01", "LV02", "LV03"}) expected += entryOf(table, tag).size;
    EXPECT_EQ(lazy->bytesRead(), expected);
    lazy->loadLevels(2);
    EXPECT_EQ(lazy->bytesRead(), expected);
    for (std::uint32_t l = 0; l <= 3; ++l) EXPECT_EQ(lazy->levels[l], built.levels[l]) << l;
    for (std::uint32_t l = 4; l < lazy->levelCount(); ++l) EXPECT_TRUE(lazy->levels[l].empty()) << l;
    // The deepest level clamps; then the whole file has been read, and the tree is readVto's.
    lazy->loadLevels(99);
    EXPECT_EQ(lazy->bytesRead(), bytes.size());
    EXPECT_EQ(*lazy, readVto(path));
    EXPECT_EQ(readVto(path).bytesRead(), bytes.size());
}

TEST(LazyVto, CopyingALazyTreeLoadsEveryLevel) {
    const Octree built = scatteredOctree(4);
    const fs::path path = writeTree(built, "copy.vto");
    const auto lazy = openVto(path);
    const Octree copy = *lazy;  // a plain, complete tree
    for (std::uint32_t l = 0; l < copy.levelCount(); ++l) EXPECT_EQ(copy.levels[l], built.levels[l]) << l;
    EXPECT_EQ(copy.storedNodes(), built.storedNodes());
    EXPECT_EQ(openVto(path)->storedNodes(), built.storedNodes());
}

TEST(LazyVto, ADamagedLevelFailsOnlyWhenItIsUsedNamingFileAndSection) {
    const Octree built = scatteredOctree(5);
    const fs::path path = writeTree(built, "damaged.vto");
    std::string bytes = readBytes(path);
    const auto lv5 = entryOf(sectionTable(bytes), "LV05");
    bytes[lv5.offset + lv5.size / 2] = char(bytes[lv5.offset + lv5.size / 2] ^ 0x10);
    writeBytes(path, bytes);
    EXPECT_THROW(readVto(path), InputError);  // the eager reader checks everything
    const auto lazy = openVto(path);
    lazy->loadLevels(4);
    EXPECT_EQ(lazy->levels[4], built.levels[4]);
    for (int attempt = 0; attempt < 2; ++attempt) {  // a failed load is not remembered as done
        try {
            lazy->loadLevels(5);
            ADD_FAILURE() << "damaged LV05 not detected";
        } catch (const InputError& e) {
            EXPECT_EQ(e.file(), path);
            EXPECT_EQ(e.location(), "section 'LV05'");
            EXPECT_NE(std::string(e.what()).find("checksum mismatch"), std::string::npos) << e.what();
        }
    }
    EXPECT_TRUE(lazy->levels[5].empty());
}

TEST(LazyVto, AHeaderProblemIsRefusedAtOpenAsReadVtoRefusesIt) {
    const Octree built = scatteredOctree(6);
    const fs::path path = writeTree(built, "header.vto");
    const std::string bytes = readBytes(path);
    const auto table = sectionTable(bytes);
    const auto expectSameRefusal = [&](const std::string& damaged, const char* what) {
        writeBytes(path, damaged);
        std::string eager, lazy;
        try {
            readVto(path);
        } catch (const InputError& e) {
            eager = e.what();
        }
        try {
            openVto(path);
        } catch (const InputError& e) {
            lazy = e.what();
        }
        EXPECT_FALSE(lazy.empty()) << what;
        EXPECT_EQ(lazy, eager) << what;
    };
    std::string magic = bytes;
    magic[0] = 'X';
    expectSameRefusal(magic, "magic");
    std::string tableByte = bytes;
    tableByte[detail::kHeaderSize + 9] ^= 1;  // an offset in the table
    expectSameRefusal(tableByte, "table");
    std::string head = bytes;
    head[entryOf(table, "STAT").offset + 3] ^= 1;
    expectSameRefusal(head, "STAT");
    expectSameRefusal(bytes.substr(0, 20), "truncated header");
    expectSameRefusal(bytes.substr(0, bytes.size() - 7), "truncated last level");
    expectSameRefusal(bytes + "extra", "trailing bytes");
    fs::remove(path);
    EXPECT_THROW(openVto(path), InputError);
}

TEST(LazyVto, TheOpenFileIsReadAsItWasWhenReplacedAndRefusedWhenChangedInPlace) {
    const Octree first = scatteredOctree(7), second = scatteredOctree(8);
    const fs::path path = writeTree(first, "replaced.vto");
    const auto lazy = openVto(path);
    writeVto(second, path);  // by rename, as every vtex writer does
    lazy->loadLevels(99);
    EXPECT_EQ(*lazy, first);

    const fs::path inPlace = writeTree(first, "in_place.vto");
    const auto opened = openVto(inPlace);
    std::string bytes = readBytes(inPlace);
    const auto lv3 = entryOf(sectionTable(bytes), "LV03");
    bytes[lv3.offset + 9] ^= 0x40;
    {
        std::fstream f(inPlace, std::ios::binary | std::ios::in | std::ios::out);  // same inode
        f.seekp(std::streamoff(lv3.offset + 9));
        f.put(bytes[lv3.offset + 9]);
    }
    EXPECT_THROW(opened->loadLevels(3), InputError);
    std::filesystem::resize_file(inPlace, lv3.offset + 4);
    EXPECT_THROW(opened->loadLevels(3), InputError);  // truncated since it was opened
}

TEST(LazyVto, ConcurrentFirstUsesLoadEachLevelOnceAndAgree) {
    const Octree built = scatteredOctree(9);
    const fs::path path = writeTree(built, "threads.vto");
    const std::uint64_t fileSize = fs::file_size(path);
    for (int round = 0; round < 8; ++round) {
        const auto lazy = openVto(path);
        std::vector<std::thread> threads;
        for (int t = 0; t < 8; ++t)
            threads.emplace_back([&, t] {
                const std::uint32_t level = std::uint32_t((t * 5 + round) % 7);
                lazy->loadLevels(level);
                // Every node of every loaded level, as a march would read them.
                for (std::uint32_t l = 0; l <= level; ++l) EXPECT_EQ(lazy->levels[l], built.levels[l]);
            });
        for (auto& thread : threads) thread.join();
        lazy->loadLevels(6);
        EXPECT_EQ(lazy->bytesRead(), fileSize);  // each section read exactly once
    }
}

}  // namespace
}  // namespace vtex::octree
