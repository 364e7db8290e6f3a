/// @file
/// @brief Procedural source meshes: the paper's scripts of primitives, as ordinary meshes.
///
/// F. Neyret 1994: grass (Fig. 7: blades of decreasing V section in a cyclic volume), bush
/// (Figs. 5–6: up to 2000 leaves), fur (Figs. 8 and 10: thin cylinders, cyclic), brushed
/// aluminium (Fig. 1: concentric cylinders turning into spheres, or radial cylinders) and
/// building blocks (Fig. 11: elements sometimes thinner than a voxel), topiary (Fig. 5: a bush
/// trimmed to a ball of leaves, a block of needles or a cone of beads, in a frame). Every pattern lies in the
/// unit reference cube, z up, and is deterministic for a seed (its own generator, not the
/// platform's distributions). Cyclic patterns are tileable: whatever crosses the tile's x or y
/// border is cut there and the cut-off part is moved to the opposite side, so the mesh stays in
/// [0,1]² × [0,1] and copies placed side by side join without seams.
#pragma once

#include <vtex/ingest/mesh.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace vtex::sampler {

struct PatternOptions {
    std::uint64_t seed = 1;
    /// Number of elements: blades (grass, default 16), leaves (bush, default 2000), hairs (fur,
    /// default 300), rings or spokes (brushed, default 9 / 24), elements (blocks, default 24;
    /// topiary, default 2000, beads 1500).
    /// 0 = the default.
    int count = 0;
    /// Angular fluctuation of the elements' directions, radians (standard deviation); < 0 = the
    /// pattern's default (grass 0.25, fur 0.15).
    double fluctuation = -1;
    /// Mean lean of blades and hairs from the vertical toward +x, degrees.
    double leanDegrees = 0;
    /// brushed: "concentric" (default) or "radial"; topiary: "leaves" (default), "needles" or "beads".
    std::string variant;
};

/// grass, bush, fur, brushed, blocks, topiary.
const std::vector<std::string>& patternNames();
/// Whether `pattern` reads the option `option` ("seed", "count", "fluctuation", "lean",
/// "variant"): every pattern takes a seed and a count, grass and fur a fluctuation and a lean,
/// brushed and topiary a variant. An option a pattern does not use is refused by the command line and the
/// pipeline file rather than silently ignored.
bool patternUses(std::string_view pattern, std::string_view option);
/// The patterns that use `option`, as "grass and fur", for messages.
std::string patternsUsing(std::string_view option);

/// Whether a pattern is tileable in x and y (grass and fur): sample it with `cyclic`.
bool isCyclicPattern(std::string_view name);

/// The most triangles a pattern may have: what ingest accepts by default
/// (ingest::IngestOptions::maxTriangles), so that `vtex sample` and a pipeline can read it.
inline constexpr std::uint64_t kMaxPatternTriangles = 50'000'000;

/// About how many triangles makePattern() would make: exact up to 64 elements, else those of 64
/// elements scaled to the count (every pattern grows linearly with its count). Cheap. Throws
/// like makePattern() for a bad option.
std::uint64_t estimatePatternTriangles(std::string_view name, const PatternOptions& options);

/// Generates a pattern. Throws std::invalid_argument for an unknown name, a bad option, or a
/// count whose mesh would have more than kMaxPatternTriangles (`brushed --variant radial --count
/// 2097152` asked for about 10⁹ triangles and grew past 6 GB; found by fuzz_cli.py).
ingest::TriangleMesh makePattern(std::string_view name, const PatternOptions& options);

/// Cuts `mesh` along the planes x = k and y = k (integers) and moves every piece into the unit
/// tile [0,1)², interpolating normals and UVs, so the area is unchanged; what lies below z = 0
/// or above z = 1 is cut away. Used by cyclic patterns.
ingest::TriangleMesh wrapIntoUnitTile(const ingest::TriangleMesh& mesh);

}  // namespace vtex::sampler
