// The S of random stored voxels of every level of a 64³ `bush` texel (400 leaves): the shapes a
// render of the bush shades, shared by the specular estimators' table and the shading benchmark.
#pragma once

#include <vtex/core/progress.h>
#include <vtex/octree/octree.h>
#include <vtex/primitive/packing.h>
#include <vtex/sampler/patterns.h>
#include <vtex/sampler/sampler.h>

#include <Eigen/Dense>

#include <algorithm>
#include <random>
#include <vector>

namespace vtex::bench {

inline std::vector<Eigen::Matrix3d> bushVoxels(std::mt19937& rng, int count) {
    sampler::PatternOptions pattern;
    pattern.count = 400;
    const auto mesh = sampler::makePattern("bush", pattern);
    sampler::SampleOptions sampling;
    sampling.resolution = 64;
    NullProgress progress;
    const auto tree = octree::buildOctree(sampler::sampleMesh(mesh, sampling, progress), {}, progress);
    std::vector<Eigen::Matrix3d> all;
    for (const auto& level : tree.levels)
        for (const auto& node : level)
            if (!node.data.isEmpty()) all.push_back(primitive::unpackS(node.data.rotation, node.data.sigma).matrix());
    std::shuffle(all.begin(), all.end(), rng);
    all.resize(std::min<std::size_t>(all.size(), std::size_t(count)));
    return all;
}

}  // namespace vtex::bench
