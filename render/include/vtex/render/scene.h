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

struct SurfaceDef {
    std::filesystem::path mesh;    ///< base quad mesh (resolved against the scene file)
    std::optional<std::size_t> texel;  ///< index into Scene::texels; none for a plain surface
    double height = 0.1;           ///< shell height H, world units
    Placement placement = Placement::On;
    std::array<double, 2> repeat{1, 1};  ///< copies of the reference volume along u and v
    Material material;
    /// The mesh, when the caller provides it in memory (tests); otherwise read from `mesh`.
    std::shared_ptr<const ingest::QuadMesh> meshData;
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

/// Every file a render of `scene` may read: the scene file, each surface's mesh, each texel's
/// volume and source (empty paths left out). What a command checks its outputs against.
std::vector<std::filesystem::path> sceneFiles(const Scene& scene);

}  // namespace vtex::render
