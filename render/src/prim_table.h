// The scene's primitives, one per base face, stored as what they are made from (a face of a base
// mesh and the surface placing it), and put together on demand: a face's corners, normals,
// trilinear cell and cell map take ~560 bytes in double precision, which a million faces cannot
// afford (issue 18: a 10⁶-face base mesh within 300 MB), while rebuilding them costs a few hundred
// instructions, next to the six patch tests of a ray entering a cell. Tables that fit a small
// budget keep them built instead (keepBuilt).
#pragma once

#include <vtex/ingest/base_mesh.h>
#include <vtex/render/cell_map.h>
#include <vtex/render/geometry.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace vtex::render::detail {

/// A base face as the renderers use it, put together by PrimTable (by value: it lives as long as
/// the caller keeps it).
struct Prim {
    int index = -1;    ///< in its PrimTable
    int surface = 0;   ///< SceneGeometry::surfaces
    int face = 0;      ///< in its base mesh
    bool textured = false;
    std::array<Vec3, 4> p;  ///< corners p00, p10, p01, p11 (world)
    std::array<Vec3, 4> n;  ///< unit shading normals at the corners
    TrilinearCell cell;     ///< textured faces only
    CellMap map;            ///< textured faces: cell → tiled reference coordinates (cell_map.h)
    /// An affine cell's localScale (footprint.h) and the inverse of its tiledJacobian (frame.h),
    /// the same at every point of it: kept, since every camera span and shadow query asks for
    /// them (a determinant, a cube root and a 3×3 inverse; libm's cbrt alone was 1.3 % of the bush
    /// field's middle view). Unset for a trilinear cell, whose Jacobian varies. (Its own flag:
    /// a plain face's default-constructed cell says affine() too.)
    bool affine = false;
    double affineScale = 0;
    Mat3 affineJacobianInverse = Mat3::Identity();
};

class PrimTable {
public:
    /// What a surface placing gives its faces: the base mesh, and for a textured placing its
    /// shell (height, under) and map (placing). `cell`: its faces are texel cells; otherwise
    /// plain patches (with `floor`, the patch of the cell's floor w = 0, for a placing with a
    /// texel drawn by other means).
    struct Surface {
        std::shared_ptr<const ingest::QuadMesh> mesh;
        bool cell = false, floor = false;
        double height = 0;
        bool under = false;
        TexelPlacing placing;
    };

    /// Adds a surface placing: they are numbered in the order added (as SceneGeometry::surfaces),
    /// which add() takes.
    void addSurface(Surface surface) {
        mSurfaces.push_back(std::move(surface));
        mBuilt.clear();
    }
    /// Adds face `face` of surface `surface`'s mesh (its corners checked by the caller).
    void add(int surface, std::uint32_t face) {
        mFaces.push_back({std::uint32_t(surface), face});
        mBuilt.clear();
    }

    /// Puts every primitive together once and keeps it, if the whole table takes at most
    /// `maxBytes`: a bush field's 400 faces take 0.2 MB, and not rebuilding a primitive (its
    /// cell's corners, normals and map) for every ray that meets it saves ~3 % of its render's
    /// instructions (docs/render.md, "Geometry"). A mesh too large for that (issue 18's million
    /// faces) keeps being put together on demand. operator[], cell(), patch() and map() then
    /// return copies of what is kept; adding a face or a surface drops it.
    void keepBuilt(std::size_t maxBytes);

    std::size_t size() const { return mFaces.size(); }
    bool empty() const { return mFaces.empty(); }
    /// Primitive i, whole.
    Prim operator[](std::size_t i) const;
    /// Primitive i without a copy when it is kept (keepBuilt); otherwise put together in
    /// `scratch`. A hot loop's way: copying a kept primitive (560 bytes) for every ray that met
    /// it was 1 % of the bush field's middle view.
    const Prim& at(std::size_t i, std::optional<Prim>& scratch) const {
        if (!mBuilt.empty()) return mBuilt[i];
        return scratch.emplace(build(i));
    }
    /// What a ray test needs, without the rest: whether primitive i is a cell, its cell (cells
    /// only), its patch corners p00, p10, p01, p11 (plain patches only).
    bool textured(std::size_t i) const { return mSurfaces[mFaces[i].surface].cell; }
    TrilinearCell cell(std::size_t i) const;
    std::array<Vec3, 4> patch(std::size_t i) const;
    /// Its cell map (cells only).
    CellMap map(std::size_t i) const;

private:
    struct Face {
        std::uint32_t surface, face;
    };
    std::vector<Surface> mSurfaces;
    std::vector<Face> mFaces;
    std::vector<Prim> mBuilt;  ///< all primitives (keepBuilt), or empty

    Prim build(std::size_t i) const;
};

}  // namespace vtex::render::detail
