#include <vtex/pipelines/demo.h>

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <map>
#include <functional>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace vtex::pipelines {
namespace {

namespace fs = std::filesystem;
using Point = std::array<double, 3>;

// A quad grid of nu × nv faces from a parametric surface, counter-clockwise seen from the side
// the normal ∂u × ∂v points to, written as OBJ.
void writeGridObj(const fs::path& file, int nu, int nv, bool wrapU, bool wrapV,
                  const std::function<Point(double, double)>& surface, const std::string& comment) {
    std::ostringstream obj;
    obj.precision(9);
    obj << "# vtex demo: " << comment << ", " << nu * nv << " bilinear faces\n";
    const int columns = wrapU ? nu : nu + 1, rows = wrapV ? nv : nv + 1;
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < columns; ++i) {
            const Point p = surface(double(i) / nu, double(j) / nv);
            obj << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
        }
    auto index = [&](int i, int j) { return (j % rows) * columns + (i % columns) + 1; };  // OBJ counts from 1
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i)
            obj << "f " << index(i, j) << ' ' << index(i + 1, j) << ' ' << index(i + 1, j + 1) << ' '
                << index(i, j + 1) << '\n';
    writeFileAtomically(file, obj.str());
}

// A round hill: a height field over [-sx, sx] × [-sy, sy].
std::function<Point(double, double)> hill(double sx, double sy, double height, double spread) {
    return [=](double u, double v) {
        const double x = sx * (2 * u - 1), y = sy * (2 * v - 1);
        return Point{x, y, height * std::exp(-(x * x + y * y) / spread)};
    };
}

struct Shot {
    Point eye, target;
    double fov;
};

std::string vector(const Point& p) {
    char text[96];
    std::snprintf(text, sizeof text, "[%.6g, %.6g, %.6g]", p[0], p[1], p[2]);
    return text;
}

std::string coverName(std::size_t i) { return i == 0 ? "cover" : "cover" + std::to_string(i + 1); }

// A surface covered with a texel: its base mesh, shell height, repeat and ground colour, and the
// demo's texel build it carries.
struct Cover {
    std::string mesh;
    double shellHeight;
    std::array<double, 2> repeat;
    Point ground;
    std::string texel;
};

// Surfaces covered with texels, under a low sun (travelling along `light`). The pipeline binds
// each scene texel (`cover`, then `cover2`, …) to the build it names; the scene names that
// build's files (DIR/builds, DIR/sources, relative to DIR/inputs) as well, so that after the
// demo `vtex render DIR/inputs/SCENE.toml` renders it on its own. One cover writes the text it
// always has (its renders stay cached).
void writeScene(const fs::path& file, const std::string& title, const Shot& shot, int width, int height,
                const std::vector<Cover>& covers, const Point& light = {-0.6, 0.5, -0.8}) {
    std::ostringstream toml;
    toml << "# vtex demo: " << title << "\n"
         << "[camera]\nposition = " << vector(shot.eye) << "\nlook_at = " << vector(shot.target)
         << "\nup = [0.0, 0.0, 1.0]\nfov_y = " << shot.fov << "\nwidth = " << width << "\nheight = " << height
         << "\n\n[[light]]\ntype = \"directional\"\ndirection = [" << light[0] << ", " << light[1] << ", " << light[2]
         << "]\ncolor = [2.8, 2.7, 2.5]\n";
    for (std::size_t i = 0; i < covers.size(); ++i)
        toml << "\n[[texel]]\nname = \"" << coverName(i) << "\"\nvolume = \"../builds/" << covers[i].texel
             << ".vto\"\nsource = \"../sources/" << covers[i].texel << ".glb\"\ntau = 1.0\n"
             << "material = { diffuse = [1.0, 1.0, 1.0], specular = [0.04, 0.04, 0.04], shininess = 20.0, "
                "ambient = [0.04, 0.045, 0.05] }\n";
    for (std::size_t i = 0; i < covers.size(); ++i)
        toml << "\n[[surface]]\nmesh = \"" << covers[i].mesh << "\"\ntexel = \"" << coverName(i)
             << "\"\nheight = " << covers[i].shellHeight << "\nplacement = \"on\"\nrepeat = [" << covers[i].repeat[0]
             << ", " << covers[i].repeat[1] << "]\n"
             << "material = { diffuse = " << vector(covers[i].ground) << ", ambient = [0.02, 0.02, 0.02] }\n";
    writeFileAtomically(file, toml.str());
}

// The demo's base meshes and the sphere of Fig. 6, into `inputs`.
void writeDemoMeshes(const fs::path& inputs) {
    const double pi = std::numbers::pi;
    writeGridObj(inputs / "hill-1404.obj", 36, 39, false, false, hill(9, 9.75, 3, 40), "Fig. 7, a hill");
    writeGridObj(inputs / "torus-240.obj", 20, 12, true, true,
                 [pi](double u, double v) {
                     const double a = 2 * pi * u, b = 2 * pi * v, r = 2 + 0.8 * std::cos(b);
                     return Point{r * std::cos(a), r * std::sin(a), 0.8 * std::sin(b)};
                 },
                 "Fig. 10, a torus");
    writeGridObj(inputs / "hill-578.obj", 17, 34, false, false, hill(6, 12, 2.5, 30), "Fig. 9, a hill");
    writeGridObj(inputs / "plane-81.obj", 9, 9, false, false,
                 [](double u, double v) { return Point{9 * u - 4.5, 9 * v - 4.5, 0}; }, "Fig. 11, a plane");
    writeGridObj(inputs / "quad.obj", 1, 1, false, false,
                 [](double u, double v) { return Point{2 * u - 1, 2 * v - 1, 0}; }, "one face");
    writeGridObj(inputs / "quad-left.obj", 1, 1, false, false,
                 [](double u, double v) { return Point{2 * u - 2.05, 2 * v - 1, 0}; }, "Fig. 1, the left face");
    writeGridObj(inputs / "quad-right.obj", 1, 1, false, false,
                 [](double u, double v) { return Point{2 * u + 0.05, 2 * v - 1, 0}; }, "Fig. 1, the right face");
    writeGridObj(inputs / "field-bushes.obj", 5, 100, false, false,
                 [](double u, double v) { return Point{5 * u, 100 * v, 0}; }, "Fig. 6, the bushes' half");
    writeGridObj(inputs / "field-spheres.obj", 5, 100, false, false,
                 [](double u, double v) { return Point{5 + 5 * u, 100 * v, 0}; }, "Fig. 6, the spheres' half");
    for (int i = 0; i < 3; ++i)
        writeGridObj(inputs / ("fig5-face-" + std::to_string(i + 1) + ".obj"), 1, 1, false, false,
                     [i](double u, double v) { return Point{2.2 * (u + i) - 3.3, 2.2 * v - 1.1, 0}; },
                     "Fig. 5, one of three faces");
    writeGridObj(inputs / "bump-256.obj", 16, 16, false, false, hill(3, 3, 1.2, 2.5), "Fig. 8, a bump");
    // Fig. 6's other texel: a sphere, as a source file (a UV sphere; the poles' rings stop short
    // of the poles, whose quads would collapse).
    writeGridObj(inputs / "sphere.obj", 48, 24, true, false,
                 [pi](double u, double v) {
                     const double a = 2 * pi * u, b = pi * (0.02 + 0.96 * v);
                     return Point{std::sin(b) * std::cos(a), std::sin(b) * std::sin(a), -std::cos(b)};
                 },
                 "a sphere");
}

// One scene per figure (and the study's), `width` × `height` pixels (Figs. 1's and 4's square
// sizes from `height`).
void writeDemoScenes(const fs::path& inputs, int width, int height) {
    const Point soil{0.30, 0.24, 0.16}, grey{0.45, 0.45, 0.47};
    writeScene(inputs / "fig7-grass-hill.toml", "Fig. 7, grass on a hill of 1404 faces", {{0, -19, 4.2}, {0, 0, 1.4}, 40},
               width, height, {{"hill-1404.obj", 0.3, {2, 2}, soil, "grass"}});
    writeScene(inputs / "fig6-bush-field.toml", "Fig. 6, bushes and spheres tiling a 50x500 region to the horizon",
               {{5, -1.5, 0.9}, {5, 30, 0}, 50}, width, height,
               {{"field-bushes.obj", 0.2, {5, 5}, soil, "bush"}, {"field-spheres.obj", 0.2, {5, 5}, soil, "spheres"}});
    writeScene(inputs / "fig10-fur-torus.toml", "Fig. 10, fur on a torus of 240 faces", {{0, -6.2, 4.2}, {0, 0, 0}, 40},
               width, height, {{"torus-240.obj", 0.15, {2, 1}, grey, "fur"}});
    writeScene(inputs / "fig9-forest-hill.toml", "Fig. 9, a forest on a hill of 578 faces",
               {{0, -25, 10}, {0, 0, 0.8}, 40}, width, height, {{"hill-578.obj", 0.7, {1, 1}, soil, "bush"}});
    writeScene(inputs / "fig11-blocks.toml", "Fig. 11, building elements on 81 faces", {{0, -9.5, 6.5}, {0, 0, 0}, 40},
               width, height, {{"plane-81.obj", 1.0, {1, 1}, grey, "blocks"}});
    writeScene(inputs / "fig1-brushed.toml",
               "Fig. 1, brushed aluminium: concentric cylinders turning into spheres (left), radial cylinders (right)",
               {{0, -4.4, 4.6}, {0, 0, 0.3}, 40}, width, height,
               {{"quad-left.obj", 1.0, {1, 1}, grey, "brushed"}, {"quad-right.obj", 1.0, {1, 1}, grey, "brushed-radial"}});
    writeScene(inputs / "fig5-topiary.toml",
               "Fig. 5, trimmed bushes of leaves, needles and beads, each texel in a frame whose shadow falls on its floor",
               {{0, -7.6, 5.0}, {0, 0, 0.8}, 40}, width, height,
               {{"fig5-face-1.obj", 2.2, {1, 1}, grey, "topiary-leaves"},
                {"fig5-face-2.obj", 2.2, {1, 1}, grey, "topiary-needles"},
                {"fig5-face-3.obj", 2.2, {1, 1}, grey, "topiary-beads"}});
    writeScene(inputs / "fig8-velvet.toml", "Fig. 8, velvet: cylinders orthogonal to a bump of 256 faces",
               {{0, -7.5, 4.5}, {0, 0, 0.5}, 40}, width, height, {{"bump-256.obj", 0.2, {1, 1}, grey, "velvet"}},
               {-1, 0.15, -0.7});
    writeScene(inputs / "study-forest.toml", "the forest of Fig. 9 at half size, for the error-against-time study",
               {{0, -25, 10}, {0, 0, 0.8}, 40}, std::max(16, width / 2), std::max(12, height / 2),
               {{"hill-578.obj", 0.7, {1, 1}, soil, "bush"}});
    writeScene(inputs / "fig4-bush.toml", "Fig. 4, one texel at successive octree levels", {{0, -3.2, 2.6}, {0, 0, 0.8}, 40},
               height, height, {{"quad.obj", 2.0, {1, 1}, soil, "bush"}});
}

// The pipeline: the sources, the texels, each figure with its reference and comparison, the
// Fig. 4 series and the error-against-time study.
std::string demoPipeline(const DemoOptions& options) {
    std::ostringstream p;
    p << "# vtex demo: the paper's showcase, rebuilt from the procedural patterns\n"
      << "[pipeline]\noutput = \"..\"\n\n";
    for (const char* pattern : {"grass", "bush", "fur", "brushed", "blocks"})
        p << "[[source]]\nname = \"" << pattern << "\"\npattern = \"" << pattern << "\"\nseed = " << options.seed << "\n\n";
    // Fig. 1's right half, Fig. 8's hairs all orthogonal to the surface, Fig. 6's spheres.
    p << "[[source]]\nname = \"brushed-radial\"\npattern = \"brushed\"\nvariant = \"radial\"\nseed = " << options.seed
      << "\n\n[[source]]\nname = \"velvet\"\npattern = \"fur\"\nfluctuation = 0.0\nseed = " << options.seed
      << "\n\n[[source]]\nname = \"spheres\"\nfile = \"sphere.obj\"\nfit = \"cell\"\n\n";
    // Fig. 5's three kinds of topiary, each in its frame.
    for (const char* variant : {"leaves", "needles", "beads"})
        p << "[[source]]\nname = \"topiary-" << variant << "\"\npattern = \"topiary\"\nvariant = \"" << variant
          << "\"\nseed = " << options.seed << "\n\n";
    for (const char* texel : {"grass", "bush", "fur", "brushed", "blocks", "brushed-radial", "velvet", "spheres",
                              "topiary-leaves", "topiary-needles", "topiary-beads"})
        p << "[[texel]]\nname = \"" << texel << "\"\nsource = \"" << texel << "\"\nresolution = "
          << options.maxResolution << "\n\n";
    // A scene's texels bound to builds: `texels` (a space-separated list) names the builds of
    // `cover`, `cover2`, … in turn.
    auto bindings = [](const std::string& texels) {
        std::istringstream in(texels);
        std::string text = "texels = {", texel;
        for (std::size_t i = 0; in >> texel; ++i) text += (i ? ", " : " ") + coverName(i) + " = \"" + texel + "\"";
        return text + " }";
    };
    auto render = [&](const std::string& name, const std::string& scene, const std::string& texels, double bias = 0,
                      int spp = 1) {
        p << "[[render]]\nname = \"" << name << "\"\nscene = \"" << scene << "\"\n" << bindings(texels)
          << "\nlod_bias = " << bias << "\nspp = " << spp << "\n\n";
    };
    auto reference = [&](const std::string& name, const std::string& scene, const std::string& texels, int spp) {
        p << "[[render]]\nname = \"" << name << "\"\nscene = \"" << scene << "\"\n" << bindings(texels)
          << "\nrenderer = \"reference\"\nspp = " << spp << "\n\n";
    };
    auto compare = [&](const std::string& a, const std::string& b, const std::string& name) {
        p << "[[compare]]\nname = \"" << name << "\"\na = \"" << a << "\"\nb = \"" << b << "\"\n\n";
    };
    // Each figure with its explicit-geometry reference and its measured error.
    const std::vector<std::array<std::string, 3>> figures = {
        {"fig7-grass-hill", "fig7-grass-hill.toml", "grass"},
        {"fig6-bush-field", "fig6-bush-field.toml", "bush spheres"},
        {"fig10-fur-torus", "fig10-fur-torus.toml", "fur"},
        {"fig9-forest-hill", "fig9-forest-hill.toml", "bush"},
        {"fig11-blocks", "fig11-blocks.toml", "blocks"},
        {"fig1-brushed", "fig1-brushed.toml", "brushed brushed-radial"},
        {"fig8-velvet", "fig8-velvet.toml", "velvet"},
        {"fig5-topiary", "fig5-topiary.toml", "topiary-leaves topiary-needles topiary-beads"}};
    for (const auto& [name, scene, texels] : figures) {
        render(name, scene, texels);
        reference(name + "-reference", scene, texels, options.referenceSpp);
        compare(name, name + "-reference", name + "-vs-reference");
    }
    // Fig. 4: the levels side by side, each against the reference (its error) and beside the
    // finest (a difference: the finest level is no truth, so it is the `b` each coarser level is
    // set against, and the report shows one table of differences from it).
    reference("fig4-reference", "fig4-bush.toml", "bush", options.referenceSpp);
    for (int bias = 0; bias < 4; ++bias) {
        const std::string level = "fig4-level-minus-" + std::to_string(bias);
        render(level, "fig4-bush.toml", "bush", bias);
        compare(level, "fig4-reference", level + "-vs-reference");
        if (bias > 0) compare(level, "fig4-level-minus-0", level + "-vs-finest");
    }
    // Error against run time on the forest at half the image size: texel renders per LoD bias and
    // spp, reference renders per spp, all against a reference of many samples.
    reference("study-truth", "study-forest.toml", "bush", options.studyTruthSpp);
    for (int spp : {1, 4, 16, 64}) {
        const std::string name = "study-reference-" + std::to_string(spp) + "spp";
        reference(name, "study-forest.toml", "bush", spp);
        compare(name, "study-truth", name + "-vs-truth");
    }
    for (int bias : {-1, 0, 1})
        for (int spp : {1, 4}) {
            const std::string name = "study-texel-bias" + std::string(bias < 0 ? "-" : bias > 0 ? "+" : "") +
                                     std::to_string(std::abs(bias)) + "-" + std::to_string(spp) + "spp";
            render(name, "study-forest.toml", "bush", bias, spp);
            compare(name, "study-truth", name + "-vs-truth");
        }
    return p.str();
}

}  // namespace

RunReport runDemo(const DemoOptions& options) {
    // The seed goes into the pipeline file, whose integers are signed 64-bit: a larger one made
    // a pipeline the demo could not read, after its inputs were written (found by fuzz_cli.py).
    if (options.seed > std::uint64_t(std::numeric_limits<std::int64_t>::max()))
        throw std::invalid_argument("demo: the seed must be at most 2^63 - 1");
    // The inputs are written before runPipeline() checks the folder: checked here first.
    checkOutputFolder(options.outputDirectory);
    const fs::path inputs = options.outputDirectory / "inputs";
    std::error_code error;
    fs::create_directories(inputs, error);
    if (error) throw IoError(inputs, "cannot create the output directory: " + error.message());
    const int width = std::max(16, int(std::lround(768 * options.imageScale)));
    const int height = std::max(12, int(std::lround(576 * options.imageScale)));
    writeDemoMeshes(inputs);
    writeDemoScenes(inputs, width, height);
    writeFileAtomically(inputs / "pipeline.toml", demoPipeline(options));

    RunOptions run = options.run;
    run.output = options.outputDirectory;
    run.force = options.force;
    return runPipeline(loadPipeline(inputs / "pipeline.toml"), run);
}

std::string formatDemoReport(const RunReport& report) {
    using Json = nlohmann::json;
    std::ostringstream out;
    char line[320];
    int ran = 0, cached = 0;
    std::map<std::string, Json> renders, compares;
    for (const auto& s : report.stages) {
        ran += s.status == StageRecord::Status::Ran;
        cached += s.status == StageRecord::Status::Cached;
        if (s.detailsJson.empty()) continue;
        if (s.kind == "render") renders[s.name] = Json::parse(s.detailsJson);
        if (s.kind == "compare") compares[s.name] = Json::parse(s.detailsJson);
    }
    std::snprintf(line, sizeof line, "vtex demo: %zu stages (%d run, %d cached) in %.1f s\n\n", report.stages.size(),
                  ran, cached, report.seconds);
    out << line;
    auto seconds = [](const Json& stats) { return stats.value("wall_seconds", 0.0) + stats.value("load_seconds", 0.0); };
    for (const auto& s : report.stages) {
        if (s.kind != "build" || s.detailsJson.empty()) continue;
        const auto d = Json::parse(s.detailsJson);
        std::snprintf(line, sizeof line, "  texel  %-22s %2zu levels, %9llu nodes stored, compression %.2f%%\n",
                      s.name.c_str(), d["levels"].size(), (unsigned long long)d["stored_nodes"].get<std::uint64_t>(),
                      100 * d["compression"].get<double>());
        out << line;
    }
    out << "\n  figure (texel render vs its reference)         texel    reference        RMSE    SSIM\n";
    for (const auto& [name, metrics] : compares) {
        const std::string a = metrics.value("a", ""), b = metrics.value("b", "");
        if (b.find("-reference") == std::string::npos || !renders.count(a) || !renders.count(b)) continue;
        std::snprintf(line, sizeof line, "  %-44s %6.2f s  %6.2f s %3d spp  %.4f  %.4f  -> renders/%s.png\n", a.c_str(),
                      seconds(renders[a]), seconds(renders[b]), renders[b].value("spp", 0), metrics.value("rmse", 0.0),
                      metrics.value("ssim", 0.0), a.c_str());
        out << line;
    }
    for (const auto& [name, metrics] : compares) {
        if (name.find("-vs-finest") == std::string::npos) continue;
        std::snprintf(line, sizeof line, "  %-44s RMS difference %.4f from the finest level\n",
                      metrics.value("a", "").c_str(), metrics.value("rmse", 0.0));
        out << line;
    }
    // The study's table, as the report has it.
    if (!report.errorAgainstTimeJson.empty()) {
        for (const Json& group : Json::parse(report.errorAgainstTimeJson)) {
            if (group.value("truth", "") != "study-truth") continue;
            std::snprintf(line, sizeof line, "\n  error against run time (the forest, against a %d-spp reference of %.1f s)\n",
                          renders.count("study-truth") ? renders["study-truth"].value("spp", 0) : 0,
                          group.value("truth_seconds", 0.0));
            out << line << "  render                          seconds     RMSE   speed-up over the reference of equal error\n";
            for (const Json& row : group.at("rows")) {
                std::string speedup;
                if (row.contains("speedup_at_equal_error")) {
                    const Json& sp = row["speedup_at_equal_error"];
                    std::snprintf(line, sizeof line, "%s%.2fx", sp["bound"] == "interpolated" ? "" : (sp["bound"].get<std::string>() + " ").c_str(),
                                  sp["value"].get<double>());
                    speedup = line;
                }
                std::snprintf(line, sizeof line, "  %-30s %8.3f  %7.4f   %s\n", row["render"].get<std::string>().c_str(),
                              row["seconds"].get<double>(), row["rmse"].get<double>(), speedup.c_str());
                out << line;
            }
        }
    }
    for (const auto& o : report.leftOut) out << "  left out: " << o.texel << ": " << o.reason << "\n";
    for (const auto& s : report.stages)
        if (s.status == StageRecord::Status::Failed) out << "  FAILED " << s.kind << " " << s.name << ": " << s.message << "\n";
    out << "\nReport: " << report.reportHtml.string() << " (and report.json); inputs to edit and re-run with "
        << "`vtex run`: " << (report.output / "inputs" / "pipeline.toml").string() << "\n";
    return out.str();
}

}  // namespace vtex::pipelines
