// What the texel renderer keeps of each texel a scene uses: the volume prepared for marching,
// its material and, for the mesh/volume hybrid, its source mesh and the level past which that
// mesh is traced (docs/render.md, "Mesh where the volume is not faithful").
#pragma once

#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>
#include <vtex/render/texel_march.h>
#include <vtex/octree/chord_transmittance.h>

#include "frame.h"
#include "source_bvh.h"

#include <algorithm>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

namespace vtex::render::detail {

/// A texel's source mesh in the BVH the hybrid traces, read and put together either at load or
/// the first time a ray asks for it (thread-safe: one thread loads, the others wait). With the
/// load's measures stored in the texel and its source file the one they were measured from, a
/// view whose footprints never reach the mesh level — a far view — never reads, repairs or
/// indexes the mesh (docs/render.md, "Measured once, at build").
class SourceHandle {
public:
    using Mesh = std::shared_ptr<const ingest::TriangleMesh>;
    /// No source: false in a test, never loaded.
    SourceHandle();
    /// The source's BVH over `mesh`, now.
    SourceHandle(Mesh mesh, const octree::VolumeInfo& volume);
    /// The source from `read` (a mesh, checked), placed by `volume`, when first asked for.
    SourceHandle(std::function<Mesh()> read, const octree::VolumeInfo& volume);
    SourceHandle(SourceHandle&&) noexcept;
    SourceHandle& operator=(SourceHandle&&) noexcept;
    ~SourceHandle();

    explicit operator bool() const { return mState != nullptr; }
    /// The BVH, read first if it was not (exceptions of the reading pass through, and the next
    /// call reads again).
    const SourceBvh& operator*() const;
    const SourceBvh* operator->() const { return &**this; }
    /// The mesh, read first if it was not.
    const ingest::TriangleMesh& mesh() const;
    /// Whether the mesh has been read (at load, or by a ray since).
    bool loaded() const;

private:
    struct State;
    std::unique_ptr<State> mState;
};

struct TexelRuntime {
    std::unique_ptr<const MarchVolume> volume;
    double tau = 1;
    Material material;
    /// The mesh/volume hybrid (docs/render.md, "Mesh where the volume is not faithful"): the
    /// texel's source mesh, traced where a footprint asks for a level finer than `meshLevel`
    /// (blended over the next level); no source, or the hybrid off: never.
    SourceHandle source;
    double meshLevel = std::numeric_limits<double>::infinity();
    /// The finest level the load measured as faithful, before kFinestMarchedLevel capped the
    /// levels the hybrid marches: never below the mesh level, which is chosen among the capped
    /// faithful levels (−1 without a source or with the hybrid off).
    int faithfulFinest = -1;
    /// Shadow marches never take a level coarser than this: the coarsest level whose chord
    /// transmittance is within the hybrid's tolerance of the mesh's (0 without a source). A
    /// shadow needs no antialiasing, and coarser levels are measurably too opaque.
    int coarsestShadowLevel = 0;
    /// The levels above came from what `vtex build --source` stored in the texel (the .vto's
    /// MEAS section), not from measuring at load (stats.json's `source_measures`).
    bool measuresStored = false;
    /// With the levels fitted, the shadow level per footprint level below coarsestShadowLevel:
    /// measured, between the footprint's and coarsestShadowLevel (texel_runtime.cpp,
    /// shadowLevelsFrom). Empty, or a footprint past its end: max(coarsestShadowLevel, footprint).
    std::vector<int> shadowLevels;
    /// The level a shadow march takes where its cone asks for level `footprint`: never finer than
    /// the mesh level, past which the volume is not marched (as volumeUnderMesh for camera
    /// spans). So a traced shadow's volume share under the mesh's takes L, and the one query that
    /// cannot take the mesh instead (the lattice's near march under a floor seen through less
    /// than exactFloorShadowAbove) takes L too.
    int shadowLevelFor(int footprint) const {
        const int level = shadowLevelOf(shadowLevels, coarsestShadowLevel, footprint);
        return meshLevel < level ? int(meshLevel) : level;
    }
    static int shadowLevelOf(const std::vector<int>& shadowLevels, int coarsestShadowLevel, int footprint) {
        if (footprint >= 0 && std::size_t(footprint) < shadowLevels.size()) return shadowLevels[std::size_t(footprint)];
        return std::max(coarsestShadowLevel, footprint);
    }
    /// Per level, the factor of τ fitted so that the level lets through, on chords crossing the
    /// shell from its top to its floor, what the source mesh does (octree::fitShellChords;
    /// RenderOptions::fitLevels); empty: τ at every level.
    std::vector<double> levelScale;
    /// The extinction scale τ of `level`, with its fitted factor.
    double tauAt(int level) const {
        return level >= 0 && std::size_t(level) < levelScale.size() ? tau * levelScale[std::size_t(level)] : tau;
    }
    /// Per level, the share of a voxel's matter on the surface piece a lit point of it lies on
    /// (measureOwnShares, own_share.h); empty without a source.
    std::vector<double> ownShare;
    /// The factor of its own voxel's optical depth a shadow query from a camera march's voxel
    /// takes at `level`: the piece it lights does not shadow it (docs/render.md, "A lit voxel's
    /// own leaf"). 1 where nothing was measured.
    double ownDepthFactor(int level) const {
        return level >= 0 && std::size_t(level) < ownShare.size() ? 1 - ownShare[std::size_t(level)] : 1.0;
    }
    /// The mesh's share of a camera span at continuous level `requested` (LevelChoice::requested):
    /// 0 up to the mesh level L, rising linearly to 1 at L + kMeshBlendWidth.
    double meshWeight(double requested) const { return blendedMesh(requested, kMeshBlendWidth); }
    /// The mesh's share of a shadow ray's segment, over kShadowMeshBlendWidth. Shadow rays from
    /// the mesh's own hits take the mesh alone (ShadowQueries::tracedShadow).
    double shadowMeshWeight(double requested) const { return blendedMesh(requested, kShadowMeshBlendWidth); }
    /// Rays per axis a camera span through the source mesh takes across its footprint
    /// (renderer.cpp, traceSourceSpan): 2 while the footprint is coarser than a voxel of level
    /// faithfulFinest + 1, 1 past it, so that no mesh ray stands for more than a voxel of the
    /// first level the load measured as not faithful. One ray a pixel there aliases what the
    /// volume would have averaged: the leaves of the volume at L, or, where the cap keeps faithful
    /// levels past L unmarched, the hairs and bars they resolve (docs/render.md, "Mesh where the
    /// volume is not faithful").
    int meshRaysPerAxis(double requested) const { return requested < faithfulFinest + 1 ? 2 : 1; }
    /// The width of the camera's blend, in levels: over [L, L + 0.5] rather than a whole level, the
    /// volume at L, whose voxels are up to 1.4 times the footprint there instead of twice, is
    /// marched under half the footprints it was (docs/error-vs-time.md, "The hybrid's band").
    static constexpr double kMeshBlendWidth = 0.5;
    /// The width of a shadow's blend: a whole level. A shadow's volume share is visibility
    /// filtered over its voxels; its mesh share, one point of it, aliases on the ground at one ray
    /// a pixel (on the bush field a shadow blend over half a level, like the camera's, raised the
    /// RMSE by up to 14 % between 16 and 21 units).
    static constexpr double kShadowMeshBlendWidth = 1;

private:
    double blendedMesh(double requested, double width) const {
        return source ? std::clamp((requested - meshLevel) / width, 0.0, 1.0) : 0.0;
    }
};

/// The volume's levels under the hybrid's blend: a footprint that asks for a level in (L, L + 1),
/// L = `meshLevel`, takes the mesh with weight (λ − L)/TexelRuntime::kMeshBlendWidth (meshWeight) and the volume
/// at level L alone, not L's blend toward L + 1, which the load measured as not faithful (and
/// which has eight times L's voxels). Other choices are returned as they are; `level` and
/// `requested` are always kept: they say what the footprint asked for.
inline LevelChoice volumeUnderMesh(LevelChoice choice, double meshLevel) {
    if (choice.requested > meshLevel && double(choice.coarse) == meshLevel) {
        choice.fine = choice.coarse;
        choice.fineWeight = 0;
    }
    return choice;
}

/// The shadow levels of footprint levels 0 … coarsest − 1 from the lit fractions of the fitted
/// levels (texel_runtime.cpp): per footprint level f, among the levels f … coarsest whose lit
/// fraction is within `margin` of the best one's, the finest at most `tableLevel` (the near
/// table's, NearShadowTable::kMaxLevel), else the coarsest of them.
std::vector<int> shadowLevelsFrom(const octree::LitFractions& lit, int coarsest, double margin, int tableLevel);

/// Per scene texel, a level no ray of the render asks for a finer one of (LevelChoice::requested,
/// camera spans and shadow rays alike; −∞ for a texel no surface places): every camera and
/// shadow ray's cone starts at the eye or at a point it sees, so at least the distance from the
/// eye to the scene's bounds away, and a cell's local scale is at most its size (a trilinear
/// map's Jacobian columns are means of its edges), over the cube root of its map's area scale
/// where that is below 1. The shadow lattice's node rays take a cone of the lattice's spacing
/// instead, a level of log2 of its resolution in the node's cell, one more allowed for a
/// neighbour cell up to twice as fine (ShadowQueries::nodeTransmittance). `coneSpread`: the
/// cone's width per unit distance (Integrator).
std::vector<double> finestRequestedLevels(const Scene& scene, const SceneGeometry& geometry, double coneSpread,
                                          const RenderOptions& options);

/// One entry per scene texel; those that no surface uses stay empty (not loaded). Throws
/// vtex::InputError naming a volume without a root, or a source that cannot be read.
/// `finestRequested` (finestRequestedLevels; empty: unknown) lets a texel whose stored measures
/// apply leave its source mesh unread when no ray can ask for its mesh level.
std::vector<TexelRuntime> loadTexels(const Scene& scene, const RenderOptions& options,
                                     const std::vector<double>& finestRequested = {});

}  // namespace vtex::render::detail
