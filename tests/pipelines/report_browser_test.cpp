// report.html as a reader's browser shows it: a small `vtex run` (a study with texel and reference
// renders, a study of texel renders only, a figure against its reference, a level-to-level
// difference) writes the report; every local image and link in it resolves; headless Chromium
// (Debian's `chromium`, installed by scripts/install-deps.sh) lays it out at 1280×900 without
// sideways scrolling and with every image loaded; the first screen is kept as a screenshot in
// this test's output folder.
#include "run_vtex.h"

#include <vtex/render/image.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>

namespace fs = std::filesystem;
using vtex::test::readText;
using vtex::test::runVtex;
using vtex::test::shellQuote;

namespace {

constexpr const char* kChromium = "/usr/bin/chromium";

void writeText(const fs::path& file, const std::string& text) { std::ofstream(file, std::ios::binary) << text; }

fs::path makeProject() {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "report_browser";
    fs::remove_all(dir);
    fs::create_directories(dir);
    writeText(dir / "quad.obj", "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n");
    writeText(dir / "scene.toml", R"([camera]
position = [0.0, -2.6, 1.8]
look_at = [0.0, 0.0, 0.2]
fov_y = 40.0
width = 64
height = 48
[[light]]
type = "directional"
direction = [-1.0, 0.5, -1.0]
color = [3.0, 3.0, 3.0]
[[texel]]
name = "cover"
volume = "bound-by-the-pipeline.vto"
[[surface]]
mesh = "quad.obj"
texel = "cover"
height = 0.4
)");
    std::string p = "[pipeline]\noutput = \"out\"\n[[source]]\nname = \"grass\"\npattern = \"grass\"\ncount = 12\n"
                    "[[texel]]\nname = \"grass\"\nsource = \"grass\"\nresolution = 16\n";
    auto render = [&](const std::string& name, const std::string& extra) {
        p += "[[render]]\nname = \"" + name + "\"\nscene = \"scene.toml\"\ntexels = { cover = \"grass\" }\n" + extra + "\n";
    };
    render("texel", "");
    render("texel-coarser", "lod_bias = 2");
    render("reference-1spp", "renderer = \"reference\"\nspp = 1");
    render("reference-4spp", "renderer = \"reference\"\nspp = 4");
    render("truth", "renderer = \"reference\"\nspp = 16");
    auto compare = [&](const std::string& a, const std::string& b) {
        p += "[[compare]]\nname = \"" + a + "-vs-" + b + "\"\na = \"" + a + "\"\nb = \"" + b + "\"\n";
    };
    for (const char* a : {"texel", "texel-coarser", "reference-1spp", "reference-4spp"}) compare(a, "truth");
    compare("texel", "reference-4spp");         // with the next: a study of texel renders only
    compare("texel-coarser", "reference-4spp");
    compare("texel", "reference-1spp");         // a figure: one render against its reference
    compare("texel-coarser", "texel");          // a difference: neither is the truth
    writeText(dir / "pipeline.toml", p);
    return dir;
}

std::size_t count(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
}

// Runs Chromium headless on `page` with `flags`; its stdout.
std::string chromium(const fs::path& page, const std::string& flags, const fs::path& profile) {
    const fs::path out = profile / "chromium.out";
    const std::string command = std::string("timeout 60 ") + kChromium + " --headless --disable-gpu --no-sandbox "
                                "--no-first-run --hide-scrollbars --window-size=1280,900 --user-data-dir=" +
                                shellQuote(profile.string()) + " " + flags + " " +
                                shellQuote("file://" + fs::absolute(page).string()) + " >" +
                                shellQuote(out.string()) + " 2>/dev/null";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    return readText(out);
}

TEST(ReportBrowser, EveryLinkResolvesNothingOverflowsAndTheFirstScreenIsKept) {
    if (!fs::exists(kChromium))
        FAIL() << kChromium << " is missing: this test needs Debian's chromium (bash scripts/install-deps.sh installs it)";
    const fs::path dir = makeProject();
    const auto r = runVtex({"run", (dir / "pipeline.toml").string(), "--quiet"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    const fs::path report = dir / "out" / "report.html";
    const std::string html = readText(report);

    // Every local target of src= and href= exists; nothing is fetched from the network.
    const std::regex attribute(R"((src|href)="([^"]*)\")");
    std::set<std::string> targets;
    for (auto it = std::sregex_iterator(html.begin(), html.end(), attribute); it != std::sregex_iterator(); ++it) {
        std::string target = std::regex_replace((*it)[2].str(), std::regex("&amp;"), "&");
        EXPECT_EQ(target.find("://"), std::string::npos) << "the report must not reach the network: " << target;
        EXPECT_FALSE(target.empty());
        targets.insert(target);
        EXPECT_TRUE(fs::is_regular_file(report.parent_path() / target)) << target << " does not resolve";
    }
    for (const char* expected : {"renders/texel.png", "renders/texel.exr", "renders/texel.stats.json",
                                 "compares/texel-vs-truth.diff.png", "compares/texel-vs-truth.json", "../scene.toml"})
        EXPECT_TRUE(targets.count(expected)) << "no link to " << expected;
    EXPECT_EQ(html.find("<script"), std::string::npos) << "a static page";

    // The plots list only the series they hold: two studies with texel renders, one with references.
    EXPECT_EQ(count(html, ">texel renders</text>"), 2u);
    EXPECT_EQ(count(html, ">reference renders</text>"), 1u);
    // The heat maps against the truth share one scale, which their colour bar states.
    const auto json = nlohmann::json::parse(readText(dir / "out" / "report.json"));
    std::set<double> scales;
    for (const auto& group : json["error_against_time"])
        if (group["truth"] == "truth")
            for (const auto& row : group["rows"]) scales.insert(row["heatmap_scale"].get<double>());
    ASSERT_EQ(scales.size(), 1u) << "one scale for one truth";
    EXPECT_GT(*scales.begin(), 0);
    EXPECT_GE(count(html, "class=\"colourbar\""), 3u) << "a bar per group of heat maps";
    // The level-to-level comparison is a difference, not an error.
    EXPECT_NE(html.find("Difference from texel"), std::string::npos);
    EXPECT_EQ(html.find("Against texel<"), std::string::npos) << "a texel render is not a truth";
    EXPECT_NE(html.find("Where texels win"), std::string::npos);

    // Laid out by Chromium: no sideways scrolling at 1280 px, every image decoded. The test's own
    // copy carries a script that writes the measures into the title (the report has none).
    const fs::path profile = dir / "chromium-profile";
    fs::create_directories(profile);
    const fs::path probe = report.parent_path() / "report-probe.html";
    std::string probed = html;
    probed.insert(probed.rfind("</body>"),
                  "<script>addEventListener('load',()=>{const d=document.documentElement;let broken=0;"
                  "for(const i of document.images)if(!i.complete||i.naturalWidth==0)++broken;"
                  "document.title='measure '+d.scrollWidth+' '+innerWidth+' '+broken+' '+document.images.length;});"
                  "</script>");
    writeText(probe, probed);
    const std::string dom = chromium(probe, "--run-all-compositor-stages-before-draw --virtual-time-budget=5000 --dump-dom", profile);
    std::smatch m;
    const std::string title = std::regex_search(dom, m, std::regex(R"(<title>measure (\d+) (\d+) (\d+) (\d+)</title>)"))
                                  ? m.str(0) : std::string();
    ASSERT_FALSE(title.empty()) << "the probe did not run:\n" << dom.substr(0, 400);
    const int scrollWidth = std::stoi(m.str(1)), viewport = std::stoi(m.str(2));
    EXPECT_EQ(viewport, 1280);
    EXPECT_LE(scrollWidth, viewport) << "the page scrolls sideways";
    EXPECT_EQ(std::stoi(m.str(3)), 0) << "images that did not load";
    EXPECT_GE(std::stoi(m.str(4)), 8) << "renders and heat maps";
    fs::remove(probe);

    // The first screen, kept in this test's output folder.
    const fs::path screenshot = dir / "report-first-screen.png";
    chromium(report, "--screenshot=" + shellQuote(screenshot.string()), profile);
    ASSERT_TRUE(fs::is_regular_file(screenshot));
    const vtex::render::Image shot = vtex::render::readPng(screenshot);
    EXPECT_EQ(shot.width, 1280);
    EXPECT_EQ(shot.height, 900);
    std::size_t dark = 0;
    for (std::size_t p = 0; p < shot.pixels(); ++p) dark += shot.rgba[4 * p] < 0.5f;
    EXPECT_GT(dark, shot.pixels() / 200) << "the first screen is blank";
    std::cout << "report screenshot: " << screenshot.string() << "\n";
}

}  // namespace
