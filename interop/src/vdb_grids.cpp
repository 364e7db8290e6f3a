// A texel's levels as OpenVDB grids (vdb.h, docs/export.md): the module vtex_vdb.so, which
// `vtex export` loads when it writes a .vdb (vdb_module.h says why). The only translation unit
// that includes OpenVDB's headers (~22 s to compile).
#include "vdb_module.h"

#include <vtex/interop/level_export.h>
#include <vtex/interop/vdb.h>

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <openvdb/io/Archive.h>
#include <openvdb/openvdb.h>

namespace vtex::interop {
namespace {

namespace vdb = openvdb;

// io::File::write opens the file by name itself and never reports a failed write (a full disk
// leaves a truncated file behind it). Archive's own seekable writer is what File uses; called on
// the atomic file's stream, AtomicOutputFile::finish() sees every write error.
class StreamArchive final : public vdb::io::Archive {
public:
    void writeTo(std::ostream& out, const vdb::GridCPtrVec& grids, const vdb::MetaMap& metadata) const {
        vdb::io::Archive::write(out, grids, /*seekable=*/true, metadata);
    }
};

// What every grid and the file carry: who wrote it, from what, how to read the values.
void addCommonMetadata(vdb::MetaMap& meta, const octree::Octree& octree, const VdbExportOptions& options) {
    meta.insertMeta("vtex_version", vdb::StringMetadata(options.writer));
    meta.insertMeta("vtex_source", vdb::StringMetadata(options.source));
    meta.insertMeta("vtex_filter_rule", vdb::StringMetadata(std::string(octree::filterRuleName(octree.info.rule))));
    meta.insertMeta("vtex_tolerance", vdb::FloatMetadata(octree.info.tolerance));
    meta.insertMeta("vtex_finest_level", vdb::Int32Metadata(int(octree.levelCount()) - 1));
    meta.insertMeta("vtex_tau", vdb::DoubleMetadata(options.tau));
    meta.insertMeta("vtex_scale", vdb::DoubleMetadata(options.scale));
    meta.insertMeta("vtex_cyclic", vdb::BoolMetadata(octree.info.source.cyclic));
    meta.insertMeta("vtex_voxel_centres",
                    vdb::StringMetadata(options.centres == VoxelCentres::Blender ? "blender" : "openvdb"));
    std::string along = "isotropic";
    if (options.along) {
        const auto& w = *options.along;
        along = std::to_string(w[0]) + "," + std::to_string(w[1]) + "," + std::to_string(w[2]);
    }
    meta.insertMeta("vtex_density_along", vdb::StringMetadata(along));
}

// The density grid's value of a voxel: τ·ρ/scale, times √(ωᵀSω) along a given direction ω.
float densityValue(const octree::VoxelData& voxel, const VdbExportOptions& options) {
    double extinction = options.tau / options.scale * double(voxel.density);
    if (options.along) {
        const std::array<double, 6> s = sggxEntries(voxel);
        const auto& w = *options.along;
        const double wsw = s[0] * w[0] * w[0] + s[1] * w[1] * w[1] + s[2] * w[2] * w[2] +
                           2 * (s[3] * w[0] * w[1] + s[4] * w[0] * w[2] + s[5] * w[1] * w[2]);
        extinction *= std::sqrt(std::max(wsw, 0.0));  // S is positive semi-definite: only rounding goes below 0
    }
    return float(extinction);
}

// Reference voxel (i, j, k) of level L covers [i, i+1]·2^−L; OpenVDB puts voxel centres on
// integer index coordinates, so the index → world map is scale·2^−L·(index + ½) + translate.
// Blender draws voxel i over [i, i+1] of index space: there the map has no half voxel.
vdb::math::Transform::Ptr levelTransform(std::uint32_t level, const VdbExportOptions& options) {
    const double h = options.scale / double(std::uint64_t(1) << level);
    const double half = options.centres == VoxelCentres::Blender ? 0.0 : 0.5 * h;
    vdb::math::Transform::Ptr transform = vdb::math::Transform::createLinearTransform(h);
    transform->postTranslate(
        vdb::Vec3d(options.translate[0] + half, options.translate[1] + half, options.translate[2] + half));
    return transform;
}

// The eight grids of one level.
struct LevelGrids {
    vdb::FloatGrid::Ptr density;
    vdb::Vec3SGrid::Ptr albedo;
    std::array<vdb::FloatGrid::Ptr, 6> sggx;

    std::vector<vdb::GridBase::Ptr> all() const {
        std::vector<vdb::GridBase::Ptr> grids{density, albedo};
        grids.insert(grids.end(), sggx.begin(), sggx.end());
        return grids;
    }
};

LevelGrids makeLevelGrids(std::uint32_t level, bool suffixed) {
    LevelGrids g;
    g.density = vdb::FloatGrid::create(0.f);
    g.density->setName(vdbGridName("density", level, suffixed));
    g.density->setGridClass(vdb::GRID_FOG_VOLUME);
    g.albedo = vdb::Vec3SGrid::create(vdb::Vec3s(0.f));
    g.albedo->setName(vdbGridName("albedo", level, suffixed));
    g.albedo->setVectorType(vdb::VEC_INVARIANT);  // a colour: no transform rotates or scales it
    for (std::size_t e = 0; e < 6; ++e) {
        g.sggx[e] = vdb::FloatGrid::create(0.f);
        g.sggx[e]->setName(vdbGridName(std::string("sggx_") + kSggxEntryNames[e], level, suffixed));
    }
    return g;
}

// What one grid's values are, in words, for a reader of the file without docs/export.md.
void describeGrids(const LevelGrids& g, const VdbExportOptions& options) {
    g.density->insertMeta("vtex_quantity", vdb::StringMetadata(
        options.along ? "extinction per world unit along the direction w of vtex_density_along, "
                        "tau*rho*sqrt(w^T S w)/scale"
                      : "extinction per world unit, tau*rho/scale (direction-averaged; along a unit direction w: "
                        "density*sqrt(w^T S w), S from the sggx_ grids)"));
    g.albedo->insertMeta("vtex_quantity", vdb::StringMetadata("single-scattering albedo, linear RGB"));
    for (std::size_t e = 0; e < 6; ++e)
        g.sggx[e]->insertMeta("vtex_quantity", vdb::StringMetadata(
            std::string("entry ") + kSggxEntryNames[e] +
            " of the SGGX matrix S (symmetric, mean projected area 1, reference axes = world axes)"));
}

// A constant cube's bounding box in index space (inclusive corners).
vdb::CoordBBox blockBox(const LevelBlock& block) {
    const vdb::Coord lo(int(block.origin[0]), int(block.origin[1]), int(block.origin[2]));
    return {lo, lo.offsetBy(int(block.size) - 1)};
}

LevelGrids levelGrids(const octree::Octree& octree, std::uint32_t level, const VdbExportOptions& options,
                      bool suffixed) {
    LevelGrids g = makeLevelGrids(level, suffixed);
    const std::vector<LevelBlock> blocks = levelBlocks(octree, level);
    // Constant regions first, as tiles wherever they cover a whole OpenVDB node (8³ voxels and
    // up; smaller cubes become voxels), then the single voxels through cached accessors. The
    // regions are disjoint, so neither pass touches what the other made.
    for (const LevelBlock& b : blocks) {
        if (b.size == 1) continue;
        const vdb::CoordBBox box = blockBox(b);
        g.density->fill(box, densityValue(*b.data, options), true);
        g.albedo->fill(box, vdb::Vec3s(b.data->albedo[0], b.data->albedo[1], b.data->albedo[2]), true);
        const std::array<double, 6> s = sggxEntries(*b.data);
        for (std::size_t e = 0; e < 6; ++e) g.sggx[e]->fill(box, float(s[e]), true);
    }
    auto density = g.density->getAccessor();
    auto albedo = g.albedo->getAccessor();
    std::array<vdb::FloatGrid::Accessor, 6> sggx{g.sggx[0]->getAccessor(), g.sggx[1]->getAccessor(),
                                                 g.sggx[2]->getAccessor(), g.sggx[3]->getAccessor(),
                                                 g.sggx[4]->getAccessor(), g.sggx[5]->getAccessor()};
    for (const LevelBlock& b : blocks) {
        if (b.size != 1) continue;
        const vdb::Coord ijk(int(b.origin[0]), int(b.origin[1]), int(b.origin[2]));
        density.setValue(ijk, densityValue(*b.data, options));
        albedo.setValue(ijk, vdb::Vec3s(b.data->albedo[0], b.data->albedo[1], b.data->albedo[2]));
        const std::array<double, 6> s = sggxEntries(*b.data);
        for (std::size_t e = 0; e < 6; ++e) sggx[e].setValue(ijk, float(s[e]));
    }

    const vdb::math::Transform::Ptr transform = levelTransform(level, options);
    describeGrids(g, options);
    for (const vdb::GridBase::Ptr& grid : g.all()) {
        grid->setTransform(transform);  // shared: the grids of a level are aligned
        addCommonMetadata(*grid, octree, options);
        grid->insertMeta("vtex_level", vdb::Int32Metadata(int(level)));
    }
    return g;
}

// The grids of every level asked for (writeVdb has checked the levels), written to `file`.
std::vector<VdbLevelSummary> writeGrids(const octree::Octree& octree, const VdbExportOptions& options,
                                        const std::filesystem::path& file) {
    const std::vector<std::uint32_t>& levels = options.levels;
    vdb::initialize();  // registers the grid and metadata types; idempotent and thread-safe
    AtomicOutputFile out(file);  // before the grids: an unwritable path fails before any work
    vdb::GridCPtrVec grids;
    std::vector<VdbLevelSummary> summary;
    for (std::uint32_t level : levels) {
        const LevelGrids g = levelGrids(octree, level, options, levels.size() > 1);
        const vdb::FloatTree& tree = g.density->tree();
        summary.push_back({level, tree.activeVoxelCount(), tree.activeLeafVoxelCount(), tree.activeTileCount(),
                           tree.memUsage()});
        for (const vdb::GridBase::Ptr& grid : g.all()) grids.push_back(grid);
    }
    vdb::MetaMap fileMeta;
    addCommonMetadata(fileMeta, octree, options);
    std::string levelList;
    for (std::uint32_t level : levels) levelList += (levelList.empty() ? "" : ",") + std::to_string(level);
    fileMeta.insertMeta("vtex_levels", vdb::StringMetadata(levelList));
    try {
        StreamArchive().writeTo(out.stream(), grids, fileMeta);
    } catch (const vdb::Exception& e) {
        throw IoError(file, std::string("OpenVDB could not write the grids: ") + e.what());
    }
    out.commit();
    return summary;
}

}  // namespace
}  // namespace vtex::interop

// The module's entry points (vdb_module.h): nothing thrown crosses back into the program.
extern "C" __attribute__((visibility("default"))) const char* vtexInteropVdbStamp() {
    static const std::string stamp = vtex::interop::detail::vdbModuleStamp();
    return stamp.c_str();
}

extern "C" __attribute__((visibility("default"))) void vtexInteropWriteVdb(
    const vtex::octree::Octree& octree, const vtex::interop::VdbExportOptions& options,
    const std::filesystem::path& file, vtex::interop::detail::VdbModuleResult& result) {
    using Result = vtex::interop::detail::VdbModuleResult;
    try {
        result.summary = vtex::interop::writeGrids(octree, options, file);
        result.kind = Result::Done;
    } catch (const vtex::InputError& e) {
        result = {Result::Input, e.what(), e.file().string(), e.problem(), e.location(), {}};
    } catch (const vtex::IoError& e) {
        std::string problem = e.what();
        const std::string prefix = e.file().string() + ": ";
        if (problem.rfind(prefix, 0) == 0) problem.erase(0, prefix.size());
        result = {Result::Io, e.what(), e.file().string(), problem, {}, {}};
    } catch (const std::exception& e) {
        result = {Result::Other, e.what(), {}, {}, {}, {}};
    } catch (...) {
        result = {Result::Other, "unknown error in the OpenVDB writer", {}, {}, {}, {}};
    }
}
