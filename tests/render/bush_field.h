// A field of the `bush` pattern's texel, with its source mesh, under a directional light: the
// render tests' scene that has everything a texel render does (the hybrid, the fitted levels,
// the shadow lattice), small enough to render in well under a second.
#pragma once

#include "fixtures.h"

#include <vtex/sampler/patterns.h>
#include <vtex/sampler/sampler.h>

#include <memory>
#include <string>

namespace vtex::render::test {

struct SourcedTexel {
    std::shared_ptr<const vtex::ingest::TriangleMesh> mesh;
    std::shared_ptr<const vtex::octree::Octree> tree;
};

// The pattern `name` with `count` elements, sampled at `resolution`³ (cyclic when the pattern
// is), with its source mesh.
inline SourcedTexel makeSourcedTexel(const std::string& name, int count, int resolution) {
    vtex::sampler::PatternOptions pattern;
    pattern.count = count;
    auto mesh = std::make_shared<const vtex::ingest::TriangleMesh>(vtex::sampler::makePattern(name, pattern));
    vtex::sampler::SampleOptions sampling;
    sampling.resolution = resolution;
    sampling.cyclic = vtex::sampler::isCyclicPattern(name);
    vtex::NullProgress progress;
    const auto volume = vtex::sampler::sampleMesh(*mesh, sampling, progress);
    return SourcedTexel{mesh, std::make_shared<const vtex::octree::Octree>(vtex::octree::buildOctree(volume, {}, progress))};
}

inline SourcedTexel makeBush(int leaves, int resolution) { return makeSourcedTexel("bush", leaves, resolution); }

// The mean colour of an image's pixels.
inline Color imageMean(const Image& image) {
    Color sum = Color::Zero();
    for (std::size_t i = 0; i < image.pixels(); ++i)
        for (int c = 0; c < 3; ++c) sum[c] += image.rgba[4 * i + std::size_t(c)];
    return sum / double(image.pixels());
}

// Adds `texel` with its source mesh to a scene; returns its index.
inline std::size_t addSourcedTexel(Scene& scene, const SourcedTexel& texel, double tau = 1) {
    const std::size_t index = addTexel(scene, texel.tree, tau);
    scene.texels[index].sourceData = texel.mesh;
    return index;
}

// A small bush (400 leaves of the `bush` pattern) sampled at 64³: the benchmark's texel, scaled
// down so that a test renders in well under a second.
inline const SourcedTexel& smallBush() {
    static const SourcedTexel texel = makeBush(400, 64);
    return texel;
}

// A 3×3 field of bushes on a ground plane, Lambert only, seen from `eye`.
inline Scene bushField(const Eigen::Vector3d& eye, int size = 64, const SourcedTexel& bush = smallBush()) {
    Scene scene = baseScene(eye, Eigen::Vector3d(0.5, 0.5, 0.4), 40, size);
    scene.lights[0].direction = Eigen::Vector3d(-1, -0.5, -1).normalized();
    const auto texel = addSourcedTexel(scene, bush);
    scene.texels[texel].material.specular = Color::Zero();
    addSurface(scene, gridMesh(-1, -1, 2, 2, 0, 3), texel, 1.0);
    scene.surfaces.back().material.diffuse = Color(0.35, 0.28, 0.2);
    return scene;
}

}  // namespace vtex::render::test
