// Fig. 5 of the demo (Neyret 1994: "buissons taillés … avec divers types de primitives locales;
// le texel est entouré d'un cadre, dont on voit l'ombre sur le sol"): a bush trimmed to a shape,
// made of one kind of local element, inside a frame along the texel's edges.
#pragma once

#include <cstdint>
#include <filesystem>

namespace vtex::pipelines::detail {

enum class TopiaryShape { Ball, Block, Cone };
/// The elements: flat leaves (the sampler fits discs to them), needles (thin prisms: needles),
/// beads (octahedra: nearly round primitives).
enum class TopiaryElement { Leaves, Needles, Beads };

/// Writes an OBJ in the unit cube: `count` elements of kind `element` at uniform random points
/// of `shape`, each randomly turned (SplitMix64 from `seed`), and the 12 bars of a frame along
/// the cube's edges, whose shadow falls on the texel's floor. Atomically; throws vtex::IoError.
void writeTopiaryObj(const std::filesystem::path& file, TopiaryShape shape, TopiaryElement element, int count,
                     std::uint64_t seed);

}  // namespace vtex::pipelines::detail
