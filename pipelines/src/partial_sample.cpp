// See partial_sample.h.
#include "partial_sample.h"

#include "content_hash.h"

#include <vtex/core/error.h>
#include <vtex/ingest/ingest.h>
#include <vtex/octree/octree.h>

#include <nlohmann/json.hpp>

#include <fstream>

namespace vtex::pipelines::detail {
namespace {

// The earlier run's mesh and volume when its manifest vouches for both and for the parameters.
struct Earlier {
    ingest::TriangleMesh mesh;
    octree::SparseVolume volume;
};

std::optional<Earlier> readEarlier(const EarlierSample& earlier) {
    std::ifstream in(earlier.manifest);
    if (!in) return std::nullopt;
    try {
        const nlohmann::json j = nlohmann::json::parse(in);
        if (j.at("details").at("parameters").get<std::string>() != earlier.parameters) return std::nullopt;
        const auto& outputs = j.at("outputs");
        if (hashFile(earlier.volume) != outputs.at("volume").at("hash").get<std::string>() ||
            hashFile(earlier.sampledMesh) != outputs.at("sampled_mesh").at("hash").get<std::string>())
            return std::nullopt;
        return Earlier{ingest::loadMesh(earlier.sampledMesh), octree::readVtl(earlier.volume)};
    } catch (const std::exception&) {
        return std::nullopt;  // no earlier run to start from: sample in full
    }
}

}  // namespace

SampleResult sampleOrUpdate(const ingest::TriangleMesh& mesh, const sampler::SampleOptions& options,
                            const EarlierSample& earlier, Progress& progress) {
    if (const auto before = readEarlier(earlier)) {
        const auto region = sampler::changedRegion(before->mesh, mesh, options);
        const double n = double(options.resolution);
        if (region && double(region->max[0] - region->min[0]) * double(region->max[1] - region->min[1]) *
                              double(region->max[2] - region->min[2]) < 0.5 * n * n * n) {
            sampler::SampleOptions partial = options;
            partial.region = region;
            try {
                return {sampler::updateRegion(mesh, before->volume, partial, earlier.volume, progress), region};
            } catch (const InputError&) {
                // Sampled otherwise (a solid interior, say): the full sampling below.
            }
        }
    }
    return {sampler::sampleMesh(mesh, options, progress), std::nullopt};
}

}  // namespace vtex::pipelines::detail
