// A user's program built against an installed vtex: it must compile, link and run, and the
// libraries must compute what they do in the build tree.
#include <vtex/core/error.h>
#include <vtex/core/version.h>
#include <vtex/octree/ellipsoid.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>

int main() {
    const vtex::InputError error("in.obj", "no faces");
    if (std::strcmp(error.what(), "in.obj: no faces") != 0) return 1;
    // A unit sphere casts a shadow of area π in every direction.
    const vtex::octree::Ellipsoid sphere;
    if (std::abs(sphere.projectedArea(vtex::octree::Vec3::UnitX()) - std::numbers::pi) > 1e-12) return 2;
    std::printf("linked against vtex %s\n", vtex::kVersion);
    return 0;
}
