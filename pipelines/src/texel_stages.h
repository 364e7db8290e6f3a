// The work of the stages that make a texel (stage_graph.h): its source mesh, the volume sampled
// from it, and the octree built from that volume.
#pragma once

#include "partial_sample.h"
#include "stage_graph.h"

#include <vtex/core/memory_budget.h>

#include <cstdint>
#include <string>

namespace vtex::pipelines::detail {

/// source/NAME: a pattern made, or a mesh file ingested, into sources/NAME.glb ("mesh").
class SourceWork final : public StageWork {
public:
    SourceWork(SourceStep step, std::string header) : mStep(std::move(step)), mHeader(std::move(header)) {}
    std::string describe(const std::vector<Stage>& stages, const Stage& self) const override;
    nlohmann::json run(const std::vector<Stage>& stages, const Stage& self) const override;

private:
    SourceStep mStep;
    std::string mHeader;
};

/// The sample stage's parameters as its key holds them (besides the mesh): the sampled
/// resolution (the step's, or less when the renders need less), whether it is cyclic (the
/// step's, or the pattern's), and the solid mode. EarlierSample::parameters keeps it.
std::string sampleParameters(const TexelStep& step, std::uint32_t sampledResolution, bool cyclic, const std::string& header);

/// sample/NAME: the source mesh (input 0, "mesh") sampled into samples/NAME.vtl ("volume"), with a
/// copy of the mesh ("sampled_mesh") for the next run to find what an edit changed.
class SampleWork final : public StageWork {
public:
    SampleWork(const TexelStep& step, std::uint32_t sampledResolution, bool cyclic, EarlierSample earlier, bool force,
               MemoryBudget& budget)
        : mSolid(step.solid), mResolution(sampledResolution), mMaximumResolution(step.resolution), mCyclic(cyclic),
          mEarlier(std::move(earlier)), mForce(force), mBudget(budget) {}
    std::string describe(const std::vector<Stage>& stages, const Stage& self) const override;
    nlohmann::json run(const std::vector<Stage>& stages, const Stage& self) const override;

private:
    sampler::SolidMode mSolid;
    std::uint32_t mResolution, mMaximumResolution;
    bool mCyclic;
    EarlierSample mEarlier;
    bool mForce;
    MemoryBudget& mBudget;
};

/// The build stage's filter parameters, as its key and its details hold them.
std::string buildParameters(const TexelStep& step);

/// build/NAME: the sampled volume (input 0) filtered into builds/NAME.vto ("octree"), each level
/// measured against the source mesh (the sample's input).
class BuildWork final : public StageWork {
public:
    BuildWork(const TexelStep& step, std::string parameters, std::string header, MemoryBudget& budget)
        : mFilter(step.filter), mTolerance(step.tolerance), mParameters(std::move(parameters)), mHeader(std::move(header)),
          mBudget(budget) {}
    std::string describe(const std::vector<Stage>& stages, const Stage& self) const override;
    nlohmann::json run(const std::vector<Stage>& stages, const Stage& self) const override;

private:
    octree::FilterRule mFilter;
    double mTolerance;
    std::string mParameters;
    std::string mHeader;
    MemoryBudget& mBudget;
};

}  // namespace vtex::pipelines::detail
