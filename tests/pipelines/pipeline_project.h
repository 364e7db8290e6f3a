// The small project the `vtex run` tests share: a 4×4 quad hill, a scene over it, a tiny OBJ
// source, and a pipeline with two sources, two texels, two renders and a comparison.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace vtex::test {

namespace fs = std::filesystem;

inline void writeText(const fs::path& file, const std::string& text) { std::ofstream(file, std::ios::binary) << text; }

// The project's two texels as pipeline text, for the tests that write pipelines of their own
// renders: `grass` from the pattern, `cross` from cross.obj.
inline const std::string kGrassTexel = R"(
[[source]]
name = "grass"
pattern = "grass"
count = 8

[[texel]]
name = "grass"
source = "grass"
resolution = 16
)";
inline const std::string kCrossTexel = R"(
[[source]]
name = "cross"
file = "cross.obj"

[[texel]]
name = "cross"
source = "cross"
resolution = 8
filter = "neyret"
)";

// A project folder: a 4×4 quad hill, a scene over it, a tiny OBJ source, and a pipeline with
// two sources, two texels, two renders and a comparison.
inline fs::path makeProject(const std::string& name) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "pipelines" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::string hill;
    for (int j = 0; j <= 4; ++j)
        for (int i = 0; i <= 4; ++i)
            hill += "v " + std::to_string(-1 + 0.5 * i) + " " + std::to_string(-1 + 0.5 * j) + " " +
                    std::to_string(0.2 * ((i + j) % 2)) + "\n";
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
            const int a = j * 5 + i + 1;
            hill += "f " + std::to_string(a) + " " + std::to_string(a + 1) + " " + std::to_string(a + 6) + " " +
                    std::to_string(a + 5) + "\n";
        }
    writeText(dir / "hill.obj", hill);
    writeText(dir / "hill.toml", R"(
[camera]
position = [0.0, -3.0, 2.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0
width = 48
height = 36

[[light]]
type = "directional"
direction = [-1.0, 0.5, -1.0]
color = [3.0, 3.0, 3.0]

[[texel]]
name = "cover"
volume = "bound-by-the-pipeline.vto"

[[surface]]
mesh = "hill.obj"
texel = "cover"
height = 0.25
)");
    // Two crossed quads in the unit cube.
    writeText(dir / "cross.obj", "v 0.1 0.5 0.1\nv 0.9 0.5 0.1\nv 0.9 0.5 0.9\nv 0.1 0.5 0.9\n"
                                 "v 0.5 0.1 0.1\nv 0.5 0.9 0.1\nv 0.5 0.9 0.9\nv 0.5 0.1 0.9\n"
                                 "f 1 2 3 4\nf 5 6 7 8\n");
    // (a first empty line, as ever: AFileWithAnErrorIsRefusedBeforeAnythingRuns names "line 2")
    writeText(dir / "pipeline.toml", "\n[pipeline]\noutput = \"out\"\n" + kGrassTexel + kCrossTexel + R"(
[[render]]
name = "grass-hill"
scene = "hill.toml"
texels = { cover = "grass" }

[[render]]
name = "cross-hill"
scene = "hill.toml"
texels = { cover = "cross" }
hybrid = false  # its volume, so that every change of the texel shows in the image

[[compare]]
name = "grass-vs-cross"
a = "grass-hill"
b = "cross-hill"
)");
    return dir;
}

}  // namespace vtex::test
