// buildOctreeFromVtl (issue 13): a .vtl streamed into the builder gives the tree, the bytes and the
// errors of buildOctree(readVtl(file)); a file it does not stream (a solid interior, a damaged or
// misordered file) is read by readVtl, whose error names the problem.
#include "random_volume.h"

#include <vtex/core/error.h>
#include <vtex/octree/octree.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace vtex::octree {
namespace {

std::filesystem::path writeBytes(const std::string& name, const std::string& bytes) {
    const auto path = std::filesystem::temp_directory_path() / (name + "." + std::to_string(::getpid()) + ".vtl");
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return path;
}

// The .vto bytes of both ways of building `file`.
void expectSameTree(const std::filesystem::path& file, FilterRule rule) {
    BuildOptions options;
    options.rule = rule;
    NullProgress progress;
    EXPECT_EQ(serializeVto(buildOctreeFromVtl(file, options, progress)),
              serializeVto(buildOctree(readVtl(file), options, progress)));
}

// readVtl's message for `file`, or empty.
std::string readError(const std::filesystem::path& file) {
    try {
        (void)readVtl(file);
    } catch (const InputError& e) {
        return e.what();
    }
    return {};
}

TEST(VtlStream, SameTreeAsTheWholeVolumeAcrossSeveralPieces) {
    // Some 37,000 voxels: two of the reader's pieces, so a piece's first block is checked
    // against the last of the piece before.
    const SparseVolume volume = test::randomVolume(6, 40000, 7);
    ASSERT_GT(volume.blocks.size(), std::size_t(1) << 15);
    const auto file = writeBytes("stream_pieces", serializeVtl(volume));
    expectSameTree(file, FilterRule::Sggx);
    expectSameTree(file, FilterRule::Neyret);
    std::filesystem::remove(file);
}

TEST(VtlStream, SolidInteriorIsReadWhole) {
    SparseVolume volume = test::randomVolume(4, 300, 3);
    std::erase_if(volume.blocks, [](const VolumeBlock& b) { return mortonDecode(b.key)[2] < 8; });
    VoxelData solid;
    solid.density = 30;
    packIsotropic(solid);
    solid.albedo = {0.5f, 0.5f, 0.5f};
    volume.blocks.push_back(VolumeBlock{mortonEncode(0, 0, 0), 1, kBlockSolid, solid});
    volume.info.solidDensity = 30;
    volume.sortBlocks();
    const auto file = writeBytes("stream_solid", serializeVtl(volume));
    expectSameTree(file, FilterRule::Sggx);
    std::filesystem::remove(file);
}

TEST(VtlStream, DamagedFilesFailAsReadVtlFails) {
    SparseVolume volume = test::randomVolume(6, 40000, 11);
    const std::string good = serializeVtl(volume);
    std::string damaged = good;
    damaged[damaged.size() - 100] ^= 0x40;  // a voxel's byte: the VOXL checksum fails
    // Two blocks swapped across the pieces' boundary, the checksum made anew: out of order.
    std::swap(volume.blocks[(std::size_t(1) << 15) - 1], volume.blocks[std::size_t(1) << 15]);
    const std::string misordered = serializeVtl(volume);
    NullProgress progress;
    for (const auto& [name, bytes] : {std::pair{"stream_damaged", damaged}, std::pair{"stream_misordered", misordered},
                                      std::pair{"stream_truncated", good.substr(0, good.size() - 54)}}) {
        const auto file = writeBytes(name, bytes);
        const std::string expected = readError(file);
        ASSERT_FALSE(expected.empty()) << name;
        try {
            (void)buildOctreeFromVtl(file, BuildOptions{}, progress);
            ADD_FAILURE() << name << ": no error";
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()), expected) << name;
        }
        std::filesystem::remove(file);
    }
}

}  // namespace
}  // namespace vtex::octree
