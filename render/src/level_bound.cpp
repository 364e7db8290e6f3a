#include <vtex/render/level_bound.h>

#include <vtex/core/error.h>

#include "footprint.h"

#include <cmath>
#include <limits>

namespace vtex::render {

std::vector<TexelLevelNeed> finestUsefulLevels(const Scene& scene, const RenderOptions& options) {
    std::vector<TexelLevelNeed> needs(scene.texels.size());
    const int height = options.height > 0 ? options.height : scene.camera.height;
    const int strata = std::max(1, int(std::ceil(std::sqrt(double(std::max(options.spp, 1))))));
    const double spread = detail::coneSpread(scene.camera.fovY, std::max(height, 1), strata);
    const Vec3 eye = scene.camera.position;

    // The finest continuous level over all cells, per texel.
    std::vector<double> finest(scene.texels.size(), -std::numeric_limits<double>::infinity());
    std::vector<double> nearest(scene.texels.size(), std::numeric_limits<double>::infinity());
    for (std::size_t si = 0; si < scene.surfaces.size(); ++si) {
        const SurfaceDef& def = scene.surfaces[si];
        bool textured = false;
        for (std::size_t k = 0; k < def.placingCount(); ++k)
            if (const auto texel = def.placing(k).texel) {
                if (*texel >= scene.texels.size()) throw InputError(scene.file, "texel index out of range", "surface.texel");
                textured = true;
            }
        if (!textured) continue;
        const auto mesh = loadSurfaceMesh(scene, si);
        const std::vector<std::uint32_t> placings = facePlacings(scene, si, *mesh);
        for (std::size_t f = 0; f < mesh->quads.size(); ++f) {
            const TexelPlacing surface = def.placing(placings[f]);
            if (!surface.texel) continue;
            const std::size_t texel = *surface.texel;
            needs[texel].used = true;
            std::array<Vec3, 4> p, n;
            if (!detail::baseFaceCorners(*mesh, f, p, n))
                throw InputError(def.mesh, "face " + std::to_string(f) + " has an invalid corner");
            const TrilinearCell cell(p, n, surface.height, surface.placement == Placement::Under);
            // The face's perturbation turns and shifts its map, which changes no scale: the
            // unperturbed map gives the same local scales.
            const CellMap map = makeCellMap(surface, FaceTransform{});
            Vec3 lo = cell.corners()[0], hi = cell.corners()[0];
            for (const Vec3& c : cell.corners()) {
                lo = lo.cwiseMin(c);
                hi = hi.cwiseMax(c);
            }
            const double distance = (eye - eye.cwiseMax(lo).cwiseMin(hi)).norm();
            double scale = 0;
            for (int i = 0; i < 27; ++i)
                scale = std::max(scale, detail::localScale(cell, Vec3(0.5 * (i % 3), 0.5 * (i / 3 % 3), 0.5 * (i / 9)),
                                                           map));
            nearest[texel] = std::min(nearest[texel], distance);
            const double width = spread * distance / scale;
            const double level = width > 0 ? -std::log2(width) : std::numeric_limits<double>::infinity();
            finest[texel] = std::max(finest[texel], level);
        }
    }
    for (std::size_t t = 0; t < needs.size(); ++t) {
        if (!needs[t].used) continue;
        needs[t].nearestDistance = nearest[t];
        const double level = finest[t] - options.lodBias;
        if (!std::isfinite(level) || level > 60) {
            needs[t].unbounded = true;
            needs[t].finestLevel = 60;
        } else {
            // The blend reaches floor(level) + 1 whenever the level is not an integer.
            needs[t].finestLevel = std::max(0, int(std::floor(level)) + 1);
        }
    }
    return needs;
}

}  // namespace vtex::render
