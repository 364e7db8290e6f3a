// The pyramid's nodes and the filter of one parent (pyramid.h).
#include "pyramid.h"

#include "hash.h"

namespace vtex::octree::detail {

bool isSampled(std::uint64_t key, std::uint32_t level, std::uint64_t count, std::uint64_t samples) {
    if (samples == 0 || count <= samples) return true;
    const double fraction = double(samples) / double(count);
    const std::uint64_t threshold = std::uint64_t(fraction * 18446744073709551615.0);
    return mix64(key ^ (std::uint64_t(level) << 58)) < threshold;
}

void filterChildren(const PNode* children, std::size_t count, FilterRule rule, bool keepResult, Filtered& out) {
    out.forms.clear();
    out.weights.clear();
    out.formChildren.clear();
    out.result.reset();
    out.deferredMean.reset();
    // Eight identical children: the mean is the child itself, bit for bit (so that tolerance 0
    // collapses exactly constant regions).
    if (count == 8) {
        bool same = true;
        for (std::size_t i = 1; i < 8 && same; ++i) same = children[i].data == children[0].data;
        if (same) {
            out.data = children[0].data;
            return;
        }
    }
    double mass = 0;
    double albedo[3] = {0, 0, 0};
    for (std::size_t i = 0; i < count; ++i) {
        const VoxelData& d = children[i].data;
        const double w = d.density;
        mass += w;
        for (int c = 0; c < 3; ++c) albedo[c] += w * d.albedo[c];
        if (auto form = storedFilterForm(d, rule)) {
            out.forms.push_back(*form);
            out.weights.push_back(w);
            out.formChildren.push_back(i);
        }
    }
    VoxelData& p = out.data;
    p.density = float(mass / 8.0);
    for (int c = 0; c < 3; ++c) p.albedo[c] = mass > 0 ? float(albedo[c] / mass) : 0.0f;
    if (out.forms.empty()) {
        packIsotropic(p);
    } else if (rule == FilterRule::Sggx && !keepResult) {
        // filterFormsPacked's steps, its shape left to finishDeferred: no mean, no primitive.
        out.deferredMean = meanFilterForm(out.forms, out.weights);
        if (!out.deferredMean) packIsotropic(p);
    } else if (keepResult) {
        out.result = filterForms(out.forms, out.weights, rule);
        if (out.result) packEllipsoid(*out.result, p);
        else packIsotropic(p);
    } else if (const auto packed = filterFormsPacked(out.forms, out.weights, rule)) {
        p.rotation = packed->rotation;
        p.sigma = packed->sigma;
    } else {
        packIsotropic(p);
    }
}

void finishDeferred(std::span<VoxelData* const> parents, std::span<const Mat3> means) {
    thread_local std::vector<std::optional<primitive::PackedPrimitive>> packed;
    packed.resize(means.size());
    packSggxMeans(means, packed);
    for (std::size_t k = 0; k < parents.size(); ++k) {
        if (packed[k]) {
            parents[k]->rotation = packed[k]->rotation;
            parents[k]->sigma = packed[k]->sigma;
        } else {
            packIsotropic(*parents[k]);
        }
    }
}

// The filter error of one parent whose filter `f` of its children filterChildren has just made
// (filterError: its NDF against the mixture of its children's), with the children rebuilt as
// Ellipsoids; for the sampled nodes only.
double filterErrorOf(const PNode* children, std::size_t count, const Filtered& f, FilterRule rule) {
    if (!f.result) return 0;
    std::vector<Ellipsoid> ellipsoids;
    std::vector<double> weights;
    std::size_t form = 0;
    for (std::size_t i = 0; i < count; ++i) {
        // A child's Sggx form is its unpacked S (storedFilterForm), from which unpackEllipsoid
        // would build the Ellipsoid again: the same Ellipsoid without unpacking S twice.
        const bool hasForm = form < f.formChildren.size() && f.formChildren[form] == i;
        const auto e = rule == FilterRule::Sggx && hasForm ? Ellipsoid::fromS(f.forms[form])
                                                           : unpackEllipsoid(children[i].data);
        form += hasForm ? 1 : 0;
        if (e) {
            ellipsoids.push_back(*e);
            weights.push_back(children[i].data.density);
        }
    }
    return filterError(*f.result, ellipsoids, weights);
}

}  // namespace vtex::octree::detail
