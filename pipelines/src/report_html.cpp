// report.html: what ran and where texels win first (each study's error-against-time plot), then
// the tables, the images with their colour bars and links, and the stages' time and memory.
// Static HTML and inline SVG: no script, no network.
#include "report.h"
#include "report_svg.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/memory_budget.h>
#include <vtex/core/version.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace vtex::pipelines::detail {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

constexpr const char* kStyle =
    "body{font-family:sans-serif;margin:1.5em auto;max-width:1220px;padding:0 1em;color:#222}"
    "table{border-collapse:collapse;margin:.5em 0 1.5em;font-size:13px;max-width:100%}"
    "td,th{border:1px solid #ccc;padding:.25em .5em;text-align:left;overflow-wrap:break-word}"
    "td.files{overflow-wrap:anywhere}td.word{white-space:nowrap}"
    "th{background:#f3f3f3}td.n{text-align:right;white-space:nowrap}"
    ".failed{color:#b00}.skipped{color:#888}.verdict{font-size:15px}"
    "svg,img{max-width:100%;height:auto}"
    ".gallery{display:flex;flex-wrap:wrap;gap:.8em;align-items:flex-start}"
    "figure{margin:0;width:220px;font-size:12px}figure img{width:220px;display:block}"
    ".summary{display:flex;flex-wrap:wrap;gap:1em}.summary>div{flex:1 1 560px;min-width:0}"
    "code{font-size:12px}";

// Where the groups of comparisons sharing one truth belong (see writeReportHtml).
enum class GroupKind { Study, Figure, Difference };

class Page {
public:
    Page(const Pipeline& pipeline, const RunReport& report, const Json& errorTable)
        : mPipeline(pipeline), mReport(report), mTable(errorTable), mRoot(fs::absolute(report.output)) {
        for (const StageRecord& s : report.stages) mStages[s.kind + " " + s.name] = &s;
    }

    std::string html() const;

private:
    const StageRecord* stage(const std::string& kind, const std::string& name) const {
        const auto found = mStages.find(kind + " " + name);
        return found == mStages.end() ? nullptr : found->second;
    }
    GroupKind kindOf(const Json& group) const;
    std::string relative(const fs::path& file) const {
        return escapeHtml(fs::absolute(file).lexically_normal().lexically_relative(mRoot).generic_string());
    }
    // A link to `file` when it exists, else nothing (a failed stage left none).
    std::string link(const fs::path& file, const std::string& text) const {
        std::error_code error;
        if (!fs::is_regular_file(file, error)) return "";
        return "<a href=\"" + relative(file) + "\">" + escapeHtml(text) + "</a>";
    }
    std::string renderLinks(const std::string& render) const;
    std::string image(const fs::path& png, const std::string& caption, const std::string& links) const;
    std::string summary() const;
    std::string verdict(const Json& group) const;
    std::string plot(const Json& group) const;
    std::string studies() const;
    std::string figures() const;
    std::string differences() const;
    struct HeatMaps {
        std::string bar;      // the colour bar of the group's one scale (empty when scales differ)
        std::string figures;  // one <figure> per comparison
    };
    HeatMaps heatMaps(const Json& group, const std::string& id) const;
    std::string stageSection() const;

    const Pipeline& mPipeline;
    const RunReport& mReport;
    const Json& mTable;
    fs::path mRoot;
    std::map<std::string, const StageRecord*> mStages;
};

const RenderStep* findRender(const Pipeline& pipeline, const std::string& name) {
    for (const RenderStep& r : pipeline.renders)
        if (r.name == name) return &r;
    return nullptr;
}

// A study measures several renders against one truth; a figure one render against its reference;
// a difference compares two texel renders (Fig. 4's levels), neither of which is the truth.
GroupKind Page::kindOf(const Json& group) const {
    const RenderStep* truth = findRender(mPipeline, group.value("truth", ""));
    if (truth && truth->renderer == Renderer::Texel) return GroupKind::Difference;
    return group["rows"].size() > 1 ? GroupKind::Study : GroupKind::Figure;
}

std::string Page::renderLinks(const std::string& render) const {
    const fs::path dir = mRoot / "renders";
    std::string out = link(dir / (render + ".png"), "full size");
    for (const auto& [file, text] : {std::pair{render + ".exr", "EXR"}, {render + ".stats.json", "stats"}}) {
        const std::string l = link(dir / file, text);
        if (!l.empty()) out += (out.empty() ? "" : " · ") + l;
    }
    if (const RenderStep* step = findRender(mPipeline, render)) {
        const std::string l = link(step->scene, "scene");
        if (!l.empty()) out += (out.empty() ? "" : " · ") + l;
    }
    return out;
}

std::string Page::image(const fs::path& png, const std::string& caption, const std::string& links) const {
    std::error_code error;
    if (!fs::is_regular_file(png, error)) return "";
    return "<figure><a href=\"" + relative(png) + "\"><img src=\"" + relative(png) + "\" alt=\"" + escapeHtml(caption) +
           "\"></a><figcaption>" + escapeHtml(caption) + (links.empty() ? "" : "<br>" + links) + "</figcaption></figure>\n";
}

std::string speedupText(const Json& row) {
    if (!row.contains("speedup_at_equal_error")) return "–";
    const Json& sp = row["speedup_at_equal_error"];
    const std::string bound = sp.value("bound", "");
    return (bound == "interpolated" ? "" : bound + " ") + "×" + significant(sp["value"].get<double>());
}

std::string Page::verdict(const Json& group) const {
    const Json* best = nullptr;
    bool anyReference = false;
    for (const Json& row : group["rows"]) {
        anyReference = anyReference || row["renderer"] == "reference";
        if (row.contains("speedup_at_equal_error") &&
            (!best || row["speedup_at_equal_error"]["value"].get<double>() > (*best)["speedup_at_equal_error"]["value"].get<double>()))
            best = &row;
    }
    if (!anyReference) return "<p class=\"verdict\">No reference render in this study to weigh the texel renders' time against.</p>";
    if (!best) return "<p class=\"verdict\">No texel render in this study.</p>";
    const Json& row = *best;
    const double s = row["speedup_at_equal_error"]["value"].get<double>();
    const std::string bound = row["speedup_at_equal_error"].value("bound", "");
    std::ostringstream p;
    p << "<p class=\"verdict\">" << (s >= 1 ? "Texels win" : "Texels do not win here") << ": <b>"
      << escapeHtml(row["render"].get<std::string>()) << "</b> reaches RMSE " << significant(row["rmse"].get<double>())
      << " in " << formatSeconds(row["seconds"].get<double>()) << ", ";
    if (s >= 1)
        p << (bound == "at least" ? "at least " : bound == "at most" ? "at most " : "") << "<b>" << significant(s)
          << "× faster</b> than a reference render of the same error";
    else
        p << (bound == "at least" ? "at most " : bound == "at most" ? "at least " : "") << "<b>" << significant(1 / s)
          << "× slower</b> than a reference render of the same error";
    p << (bound == "interpolated" ? " (interpolated between reference renders)."
                                  : " (a bound: its error is beyond the reference renders' range).")
      << "</p>\n";
    return p.str();
}

std::string Page::plot(const Json& group) const {
    std::vector<PlotSeries> series = {{"texel renders", "#1b9e77", false, false},
                                      {"reference renders", "#d95f02", true, true}};
    std::vector<PlotPoint> points;
    for (const Json& row : group["rows"])
        points.push_back({row["seconds"].get<double>(), row["rmse"].get<double>(), row["renderer"] == "texel" ? 0u : 1u,
                          row["render"].get<std::string>() + ": " + formatSeconds(row["seconds"].get<double>()) +
                              ", RMSE " + significant(row["rmse"].get<double>())});
    return logLogPlot(points, series, "time to image (s: render + loading)",
                      "RMSE against " + group.value("truth", std::string()));
}

std::string Page::summary() const {
    int counts[4] = {0, 0, 0, 0};
    for (const StageRecord& s : mReport.stages) ++counts[int(s.status)];
    std::uint64_t peak = 0;
    for (const StageRecord& s : mReport.stages) peak = std::max(peak, s.peakMemoryBytes);
    std::ostringstream h;
    h << "<p>vtex " << kVersion << " ran <code>" << escapeHtml(mPipeline.file.string()) << "</code> ("
      << link(mPipeline.file, "pipeline file") << "): " << mReport.stages.size() << " stages, " << counts[0] << " run, "
      << counts[1] << " cached" << (counts[2] ? ", <b class=\"failed\">" + std::to_string(counts[2]) + " failed</b>" : "")
      << (counts[3] ? ", <span class=\"skipped\">" + std::to_string(counts[3]) + " skipped</span>" : "") << ", in "
      << formatSeconds(mReport.seconds) << "; the largest stage peak memory " << formatBytes(peak) << ". "
      << link(mReport.output / "report.json", "All figures as JSON") << ".</p>\n";
    h << "<h2>Where texels win</h2>\n<div class=\"summary\">\n";
    int shown = 0;
    for (const Json& group : mTable) {
        if (kindOf(group) != GroupKind::Study) continue;
        ++shown;
        h << "<div><h3>Against " << escapeHtml(group.value("truth", "")) << "</h3>\n" << verdict(group) << plot(group)
          << "</div>\n";
    }
    h << "</div>\n";
    if (!shown) h << "<p>No study (several renders measured against one truth) in this run.</p>\n";
    return h.str();
}

std::string cell(const Json& v) {
    if (v.is_null()) return "–";
    if (v.is_string()) return escapeHtml(v.get<std::string>());
    if (v.is_number()) return significant(v.get<double>());
    return escapeHtml(v.dump());
}

// The heat maps of a group, all at the group's one scale, with the colour bar that states it.
Page::HeatMaps Page::heatMaps(const Json& group, const std::string& id) const {
    double scale = 0;
    bool shared = true;
    std::string gallery;
    for (const Json& row : group["rows"]) {
        const double s = row.value("heatmap_scale", 0.0);
        if (scale > 0 && s != scale) shared = false;
        scale = std::max(scale, s);
        const std::string compare = row.value("compare", "");
        const fs::path dir = mRoot / "compares";
        std::string links = link(dir / (compare + ".diff.png"), "full size");
        const std::string metrics = link(dir / (compare + ".json"), "metrics");
        if (!metrics.empty()) links += " · " + metrics;
        const std::string render = link(mRoot / "renders" / (row["render"].get<std::string>() + ".png"), "render");
        if (!render.empty()) links += " · " + render;
        gallery += image(dir / (compare + ".diff.png"),
                         row["render"].get<std::string>() + (shared ? "" : " (scale " + significant(s, 2) + ")"), links);
    }
    if (gallery.empty() || !shared || !(scale > 0)) return {"", gallery};
    return {colourBar(scale, "heat maps: per-pixel RMS over R, G, B (linear radiance), one scale for the group", id),
            gallery};
}

std::string Page::studies() const {
    std::ostringstream h;
    int index = 0;
    for (const Json& group : mTable) {
        if (kindOf(group) != GroupKind::Study) continue;
        const std::string truth = group.value("truth", "");
        h << "<h3>Against " << escapeHtml(truth) << "</h3>\n<p>The truth: " << renderLinks(truth);
        if (group.contains("truth_seconds")) h << " (" << formatSeconds(group["truth_seconds"].get<double>()) << ")";
        h << ".</p>\n<table><tr><th>render</th><th>renderer</th><th>spp</th><th>LoD bias</th><th>filter</th>"
             "<th>time</th><th>RMSE</th><th>PSNR (dB)</th><th>SSIM</th><th>speed-up at equal error</th></tr>\n";
        for (const Json& row : group["rows"]) {
            const std::string name = row["render"].get<std::string>();
            const std::string linked = link(mRoot / "renders" / (name + ".png"), name);
            h << "<tr><td>" << (linked.empty() ? escapeHtml(name) : linked) << "</td><td>" << cell(row["renderer"])
              << (row["mode"].is_null() ? "" : " (" + cell(row["mode"]) + ")") << "</td><td class=\"n\">"
              << cell(row["spp"]) << "</td><td class=\"n\">" << cell(row["lod_bias"]) << "</td><td>" << cell(row["filter"])
              << "</td><td class=\"n\">" << formatSeconds(row["seconds"].get<double>()) << "</td><td class=\"n\">"
              << significant(row["rmse"].get<double>()) << "</td><td class=\"n\">"
              << (row["psnr"].is_null() ? "∞" : significant(row["psnr"].get<double>())) << "</td><td class=\"n\">"
              << significant(row["ssim"].get<double>()) << "</td><td class=\"n\">" << speedupText(row) << "</td></tr>\n";
        }
        const HeatMaps maps = heatMaps(group, "study" + std::to_string(index++));
        h << "</table>\n" << maps.bar << "<div class=\"gallery\">\n" << maps.figures << "</div>\n";
    }
    const std::string body = h.str();
    if (body.empty()) return "";
    return "<h2>Studies: error against run time</h2>\n<p>Each render measured against the render named as the truth "
           "(the <code>b</code> of its comparison); time is render plus loading, from its stats. A texel render's "
           "speed-up is the reference's time at the same error (interpolated log-log between reference renders, or a "
           "bound beyond them) over the texel render's time.</p>\n" + body;
}

// One render against its reference each: the render, the reference and the error, side by side.
std::string Page::figures() const {
    std::ostringstream h;
    for (const Json& group : mTable) {
        if (kindOf(group) != GroupKind::Figure) continue;
        const Json& row = group["rows"][0];
        const std::string render = row["render"].get<std::string>(), truth = group.value("truth", "");
        h << "<h3>" << escapeHtml(render) << "</h3>\n<table><tr><th>render</th><th>time</th><th>reference</th>"
             "<th>reference time</th><th>RMSE</th><th>PSNR (dB)</th><th>SSIM</th></tr>\n<tr><td>"
          << escapeHtml(render) << " (" << cell(row["spp"]) << " spp)</td><td class=\"n\">"
          << formatSeconds(row["seconds"].get<double>()) << "</td><td>" << escapeHtml(truth) << "</td><td class=\"n\">"
          << (group.contains("truth_seconds") ? formatSeconds(group["truth_seconds"].get<double>()) : "–")
          << "</td><td class=\"n\">" << significant(row["rmse"].get<double>()) << "</td><td class=\"n\">"
          << (row["psnr"].is_null() ? "∞" : significant(row["psnr"].get<double>())) << "</td><td class=\"n\">"
          << significant(row["ssim"].get<double>()) << "</td></tr></table>\n";
        const HeatMaps maps = heatMaps(group, "figure-" + render);
        h << "<div class=\"gallery\">\n" << image(mRoot / "renders" / (render + ".png"), render, renderLinks(render))
          << image(mRoot / "renders" / (truth + ".png"), truth, renderLinks(truth)) << maps.figures << "</div>\n"
          << maps.bar;
    }
    const std::string body = h.str();
    return body.empty() ? "" : "<h2>Figures against their references</h2>\n" + body;
}

// Comparisons whose `b` is itself a texel render: a level-to-level difference, not an error.
std::string Page::differences() const {
    std::ostringstream h;
    for (const Json& group : mTable) {
        if (kindOf(group) != GroupKind::Difference) continue;
        const std::string base = group.value("truth", "");
        h << "<h3>Difference from " << escapeHtml(base) << "</h3>\n<p>Neither image is the truth: these are "
          << "differences between texel renders (" << renderLinks(base) << "), not errors; each render's error is "
          << "measured against a reference above.</p>\n<table><tr><th>render</th><th>LoD bias</th>"
          << "<th>RMS difference</th><th>SSIM</th></tr>\n";
        for (const Json& row : group["rows"])
            h << "<tr><td>" << cell(row["render"]) << "</td><td class=\"n\">" << cell(row["lod_bias"])
              << "</td><td class=\"n\">" << significant(row["rmse"].get<double>()) << "</td><td class=\"n\">"
              << significant(row["ssim"].get<double>()) << "</td></tr>\n";
        const HeatMaps maps = heatMaps(group, "difference-" + base);
        h << "</table>\n" << maps.bar << "<div class=\"gallery\">\n" << maps.figures << "</div>\n";
    }
    const std::string body = h.str();
    return body.empty() ? "" : "<h2>Level-to-level differences</h2>\n" + body;
}

// A stage's figures in words with units, from its details.
std::string stageFigures(const StageRecord& s) {
    if (s.detailsJson.empty()) return "";
    const Json d = Json::parse(s.detailsJson);
    auto number = [&](const char* key) { return d.contains(key) && d[key].is_number() ? d[key].get<double>() : 0.0; };
    auto count = [&](const char* key) { return std::to_string(std::llround(number(key))); };
    std::ostringstream f;
    if (s.kind == "source") {
        f << count("triangles") << " triangles, " << (d.value("closed", false) ? "closed" : "open");
    } else if (s.kind == "sample") {
        f << count("resolution") << "³ voxels";
        if (number("maximum_resolution") > number("resolution")) f << " (of " << count("maximum_resolution") << "³)";
        f << ", " << count("occupied_blocks") << " occupied blocks, mean fit error "
          << significant(number("fit_error_mean"));
        if (d.value("updated_region", Json()).is_array()) f << ", re-sampled in a region";
    } else if (s.kind == "build") {
        f << (d.contains("levels") ? d["levels"].size() : 0) << " levels, " << count("stored_nodes")
          << " nodes stored, compression " << significant(100 * number("compression")) << " %";
    } else if (s.kind == "render" || s.kind == "tile") {
        // A tile's stats are a render's of its rows; an assembled render's, its tiles' summed.
        const Json rays = d.value("rays", Json::object());
        f << d.value("renderer", std::string()) << ", " << d.value("width", 0) << "×" << d.value("height", 0);
        if (d.contains("row_begin")) f << " rows " << d.value("row_begin", 0) << "–" << d.value("row_end", 0);
        if (d.contains("tiles")) f << " from " << d.value("tiles", 0) << " tiles";
        f << ", " << d.value("spp", 0) << " spp, " << significant(rays.value("primary", 0.0) / 1e6) << " M primary and "
          << significant(rays.value("shadow", 0.0) / 1e6) << " M shadow rays";
    } else if (s.kind == "compare") {
        f << d.value("a", std::string()) << " against " << d.value("b", std::string()) << ": RMSE "
          << significant(number("rmse")) << ", SSIM " << significant(number("ssim"));
    }
    return escapeHtml(f.str());
}

std::string bytesText(double bytes) { return bytes > 0 ? formatBytes(std::uint64_t(bytes)) : "–"; }
std::string secondsText(double seconds) { return formatSeconds(seconds); }

std::string Page::stageSection() const {
    std::ostringstream h;
    std::vector<BarRow> bars;
    for (const StageRecord& s : mReport.stages)
        if (s.status == StageRecord::Status::Ran) bars.push_back({s.kind + " " + s.name, {s.seconds, double(s.peakMemoryBytes)}});
    h << "<h2>Stages</h2>\n";
    if (bars.empty())
        h << "<p>Every stage was cached (or did not run): no time or memory to show.</p>\n";
    else
        h << "<p>The stages that ran: wall time, and the process's peak resident memory while each ran (stages of a "
             "wave run side by side, so it includes what ran beside it).</p>\n"
          << barChart(bars, {"wall time", "peak memory"}, {&secondsText, &bytesText});
    h << "<table><tr><th>stage</th><th>name</th><th>status</th><th>wall time</th><th>peak memory</th><th>figures</th>"
         "<th>files</th></tr>\n";
    for (const StageRecord& s : mReport.stages) {
        std::string files;
        for (const fs::path& o : s.outputs) {
            const std::string l = link(o, o.filename().string());
            if (!l.empty()) files += (files.empty() ? "" : " · ") + l;
        }
        const bool ran = s.status == StageRecord::Status::Ran;
        h << "<tr class=\"" << statusName(s.status) << "\"><td class=\"word\">" << s.kind << "</td><td>" << escapeHtml(s.name)
          << "</td><td" << (s.message.empty() ? " class=\"word\">" : ">") << statusName(s.status)
          << (s.message.empty() ? "" : ": " + escapeHtml(s.message)) << "</td><td class=\"n\">"
          << (ran ? formatSeconds(s.seconds) : "–") << "</td><td class=\"n\">"
          << (ran ? bytesText(double(s.peakMemoryBytes)) : "–") << "</td><td>" << stageFigures(s) << "</td><td class=\"files\">" << files
          << "</td></tr>\n";
    }
    h << "</table>\n";
    if (!mReport.leftOut.empty()) {
        h << "<h2>Left out (not needed by any render)</h2>\n<ul>\n";
        for (const Omission& o : mReport.leftOut)
            h << "<li><b>" << escapeHtml(o.texel) << "</b>: " << escapeHtml(o.reason) << "</li>\n";
        h << "</ul>\n";
    }
    return h.str();
}

std::string Page::html() const {
    const std::string title = "vtex run: " + mPipeline.file.filename().string();
    std::ostringstream h;
    h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>"
      << escapeHtml(title) << "</title>\n<style>" << kStyle << "</style></head><body>\n<h1>" << escapeHtml(title)
      << (mReport.succeeded() ? "" : " <span class=\"failed\">(some stages failed)</span>") << "</h1>\n";
    for (const StageRecord& s : mReport.stages)
        if (s.status == StageRecord::Status::Failed)
            h << "<p class=\"failed\">" << s.kind << " " << escapeHtml(s.name) << " failed: " << escapeHtml(s.message) << "</p>\n";
    h << summary() << studies() << figures() << differences() << stageSection() << "</body></html>\n";
    return h.str();
}

}  // namespace

std::string htmlPage(const Pipeline& pipeline, const RunReport& report, const Json& errorTable) {
    const Page page(pipeline, report, errorTable);
    return page.html();
}

}  // namespace vtex::pipelines::detail
