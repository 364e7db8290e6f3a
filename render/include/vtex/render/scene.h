/// @file
/// @brief The scene a render draws: camera, lights, texels, surfaces, Phong materials.
///
/// DESIGN.md, "Scene file" and "Radiometry". A scene is read from a `scene.toml` whose paths are
/// relative to the scene file. Missing or mistyped keys are refused with vtex::InputError naming
/// the file and the key (exit 3); unknown keys are kept as warnings. World (scene) units
/// throughout; colours are linear RGB.
#pragma once

#include <vtex/ingest/base_mesh.h>
#include <vtex/ingest/mesh.h>
#include <vtex/octree/octree.h>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vtex::render {

using Color = Eigen::Vector3d;

struct Camera {
    Eigen::Vector3d position{0, -6, 3};
    Eigen::Vector3d lookAt{0, 0, 0};
    Eigen::Vector3d up{0, 0, 1};
    double fovY = 40;  ///< vertical field of view, degrees, in (0, 180)
    int width = 768;
    int height = 576;
};

enum class LightType { Directional, Point };

struct Light {
    LightType type = LightType::Directional;
    /// Directional: the unit direction the light travels (from the light toward the scene).
    Eigen::Vector3d direction{0, 0, -1};
    /// Point: the position.
    Eigen::Vector3d position{0, 0, 0};
    /// Directional: the irradiance on a surface facing the light. Point: the intensity
    /// (irradiance color/d² at distance d).
    Color color{1, 1, 1};
};

/// Energy-normalised Phong, f = kd/π + ks (n+2)/(2π) cosⁿα, plus a constant ambient radiance.
struct Material {
    Color ambient{0, 0, 0};
    Color diffuse{0.8, 0.8, 0.8};
    Color specular{0, 0, 0};
    double shininess = 20;
};

struct TexelDef {
    std::string name;
    std::filesystem::path volume;  ///< the .vto (resolved against the scene file)
    std::filesystem::path source;  ///< the explicit geometry, for `vtex reference` (may be empty)
    double tau = 1;                ///< the paper's density → extinction constant
    /// Texel material: the voxel's diffuse colour is its albedo times `diffuse` (default 1).
    Material material{{0, 0, 0}, {1, 1, 1}, {0, 0, 0}, 20};
    /// The octree, when the caller provides it in memory (tests); otherwise read from `volume`.
    std::shared_ptr<const octree::Octree> octree;
    /// The source mesh, when the caller provides it in memory (tests); otherwise read from `source`.
    std::shared_ptr<const ingest::TriangleMesh> sourceData;
};

enum class Placement { On, Under };

/// The paper's "agrandir, déplacer ou faire tourner le volume de référence pour chaque texel"
/// (§3), to break the repetition: per face, drawn from `seed` and the face, a quarter turn of
/// the reference volume about its vertical axis, a mirror in x or y, and a shift in x and y
/// (cyclic texels only). See cell_map.h.
struct Perturbation {
    std::uint64_t seed = 0;
    bool rotate = false, mirror = false, shift = false;
    bool any() const { return rotate || mirror || shift; }
};

/// How a texel covers a face (DESIGN.md, "Base mesh and mapping"; paper §3: "pour chaque face
/// bilinéaire, un pointeur de texel indique quel motif utiliser ; on indique également si le
/// texel doit être posé sur ou sous la face"): which texel, the shell height, on or under the
/// face, and the part of the reference volume it shows.
struct TexelPlacing {
    std::optional<std::size_t> texel;  ///< index into Scene::texels; none: a plain face
    double height = 0.1;               ///< shell height H, world units
    Placement placement = Placement::On;
    std::array<double, 2> repeat{1, 1};  ///< copies of the reference volume along u and v
    /// The rectangle [x0, y0, x1, y1] of (tiled) reference space a face shows, instead of
    /// [0, 0, repeat]; beyond the unit square only for a cyclic texel.
    std::optional<std::array<double, 4>> subrect;
    Perturbation perturb;  ///< off by default
};

/// A surface's faces of one material or group (`[[surface]] texels = { name = … }`).
struct NamedPlacing {
    std::string name;
    TexelPlacing placing;
};

struct SurfaceDef {
    std::filesystem::path mesh;    ///< base quad mesh (resolved against the scene file)
    /// The faces that `texels` does not name (all faces without it): texel (none for plain faces),
    /// height, placement, repeat or sub-rectangle.
    std::optional<std::size_t> texel;
    double height = 0.1;
    Placement placement = Placement::On;
    std::array<double, 2> repeat{1, 1};
    std::optional<std::array<double, 4>> subrect;
    /// Per face material or group name (ingest::QuadMesh::faceNames; a material's name first).
    std::vector<NamedPlacing> texels;
    Perturbation perturb;  ///< the faces `texels` does not name; the entries' default
    Material material;
    /// The mesh, when the caller provides it in memory (tests); otherwise read from `mesh`.
    std::shared_ptr<const ingest::QuadMesh> meshData;

    /// Placing k: 0 the surface's own (texel, height, …), k ≥ 1 that of texels[k − 1].
    TexelPlacing placing(std::size_t k) const {
        return k == 0 ? TexelPlacing{texel, height, placement, repeat, subrect, perturb} : texels.at(k - 1).placing;
    }
    std::size_t placingCount() const { return texels.size() + 1; }
};

struct Scene {
    std::filesystem::path file;  ///< the scene file (empty for a scene built in memory)
    Camera camera;
    std::vector<Light> lights;
    std::vector<TexelDef> texels;
    std::vector<SurfaceDef> surfaces;
    std::vector<std::string> warnings;  ///< unknown keys and other non-fatal remarks
};

/// Parses scene TOML text; `file` names it in errors and anchors relative paths. Throws
/// vtex::InputError (file, problem, key).
Scene parseScene(std::string_view text, const std::filesystem::path& file);
/// Reads and parses a scene file. Throws vtex::InputError / vtex::IoError.
Scene loadScene(const std::filesystem::path& file);

/// The files the scene names, each read as the renderers read it (or the copy given in
/// memory): surface `i`'s base mesh, texel `i`'s volume (.vto) and source mesh. An
/// InputError names the scene file and the key first ("scene.toml: surface[0].mesh: hill.obj:
/// no such file").
std::shared_ptr<const ingest::QuadMesh> loadSurfaceMesh(const Scene& scene, std::size_t surface);
std::shared_ptr<const octree::Octree> loadTexelVolume(const Scene& scene, std::size_t texel);
std::shared_ptr<const ingest::TriangleMesh> loadTexelSource(const Scene& scene, std::size_t texel);

/// Per face of `mesh` (surface `surface`'s base mesh), the index of its placing
/// (SurfaceDef::placing): the `texels` entry named by the face's material, else by its group,
/// else 0. Throws vtex::InputError naming the scene file and the key of an entry that names no
/// face of the mesh (a misspelt material would otherwise leave its faces plain, silently).
std::vector<std::uint32_t> facePlacings(const Scene& scene, std::size_t surface, const ingest::QuadMesh& mesh);

/// The texels some surface places (on its own faces or through `texels`), each once, in
/// increasing index.
std::vector<std::size_t> usedTexels(const Scene& scene);

/// Whether texel `texel`'s volume is cyclic (tileable in x and y; octree::VolumeInfo::cyclic),
/// read from its header (or the octree given in memory).
bool texelIsCyclic(const Scene& scene, std::size_t texel);

/// Every file a render of `scene` may read: the scene file, each surface's mesh, each texel's
/// volume and source (empty paths left out). What a command checks its outputs against.
std::vector<std::filesystem::path> sceneFiles(const Scene& scene);

}  // namespace vtex::render
