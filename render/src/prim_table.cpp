// See prim_table.h.
#include "prim_table.h"

#include "footprint.h"
#include "frame.h"

namespace vtex::render::detail {
namespace {

// ingest::patchCorners without its checks, which buildSceneGeometry made when it added the face:
// this runs for every ray that meets a cell.
void corners(const ingest::QuadMesh& mesh, std::uint32_t face, std::array<Vec3, 4>& p, std::array<Vec3, 4>& n) {
    const std::array<std::uint32_t, 4> order = ingest::patchOrder(mesh, face);
    for (std::size_t c = 0; c < 4; ++c) {
        p[c] = mesh.positions[order[c]].cast<double>();
        n[c] = order[c] < mesh.normals.size() ? mesh.normals[order[c]].cast<double>() : Vec3(0, 0, 1);
    }
}

}  // namespace

void PrimTable::keepBuilt(std::size_t maxBytes) {
    mBuilt.clear();
    if (mFaces.size() > maxBytes / sizeof(Prim)) return;
    std::vector<Prim> built;
    built.reserve(mFaces.size());
    for (std::size_t i = 0; i < mFaces.size(); ++i) built.push_back(build(i));
    mBuilt = std::move(built);
}

Prim PrimTable::operator[](std::size_t i) const { return mBuilt.empty() ? build(i) : mBuilt[i]; }

Prim PrimTable::build(std::size_t i) const {
    const Face& f = mFaces[i];
    const Surface& s = mSurfaces[f.surface];
    Prim prim;
    prim.index = int(i);
    prim.surface = int(f.surface);
    prim.face = int(f.face);
    corners(*s.mesh, f.face, prim.p, prim.n);
    if (s.cell || s.floor) {
        prim.cell = TrilinearCell(prim.p, prim.n, s.height, s.under);
        prim.map = map(i);
        if (s.floor) prim.p = prim.cell.faceCorners(0);
        prim.textured = s.cell;
        if (prim.cell.affine()) {
            prim.affineScale = localScale(prim.cell, Vec3::Zero(), prim.map);
            prim.affineJacobianInverse = tiledJacobian(prim, Vec3::Zero()).inverse();
            prim.affine = true;
        }
    }
    return prim;
}

TrilinearCell PrimTable::cell(std::size_t i) const {
    const Face& f = mFaces[i];
    const Surface& s = mSurfaces[f.surface];
    if (!mBuilt.empty() && (s.cell || s.floor)) return mBuilt[i].cell;
    std::array<Vec3, 4> p, n;
    corners(*s.mesh, f.face, p, n);
    return TrilinearCell(p, n, s.height, s.under);
}

std::array<Vec3, 4> PrimTable::patch(std::size_t i) const {
    if (!mBuilt.empty()) return mBuilt[i].p;
    const Face& f = mFaces[i];
    const Surface& s = mSurfaces[f.surface];
    std::array<Vec3, 4> p, n;
    corners(*s.mesh, f.face, p, n);
    return s.floor ? TrilinearCell(p, n, s.height, s.under).faceCorners(0) : p;
}

CellMap PrimTable::map(std::size_t i) const {
    const Face& f = mFaces[i];
    const Surface& s = mSurfaces[f.surface];
    if (!mBuilt.empty() && (s.cell || s.floor)) return mBuilt[i].map;
    return makeCellMap(s.placing, drawFaceTransform(s.placing.perturb, f.face));
}

}  // namespace vtex::render::detail
