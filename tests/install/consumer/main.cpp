// A user's program built against an installed vtex: it must compile, link and run, and the
// libraries must compute what they do in the build tree.
#include <vtex/core/error.h>
#include <vtex/core/version.h>
#include <vtex/octree/voxel.h>
#include <vtex/primitive/ellipsoid.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>

int main() {
    const vtex::InputError error("in.obj", "no faces");
    if (std::strcmp(error.what(), "in.obj: no faces") != 0) return 1;
    // A unit sphere casts a shadow of area π in every direction.
    const vtex::primitive::Ellipsoid sphere;
    if (std::abs(sphere.projectedArea(vtex::primitive::Vec3::UnitX()) - std::numbers::pi) > 1e-12) return 2;
    // The octree stores it through the primitive library's packing: a sphere's S is the identity.
    vtex::octree::VoxelData voxel;
    voxel.density = 1;
    vtex::octree::packEllipsoid(sphere, voxel);
    const vtex::primitive::SggxMatrix s = vtex::octree::unpackS(voxel);
    if (std::abs(s.xx - 1) > 1e-6 || std::abs(s.xy) > 1e-6) return 3;
    std::printf("linked against vtex %s\n", vtex::kVersion);
    return 0;
}
