#include "report.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/version.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

#include <sys/resource.h>

namespace vtex::pipelines {
namespace {

using Json = nlohmann::json;

std::string escapeHtml(const std::string& text) {
    std::string out;
    for (char c : text) {
        switch (c) {
            case '&': out += "&amp;"; break;
            case '<': out += "&lt;"; break;
            case '>': out += "&gt;"; break;
            case '"': out += "&quot;"; break;
            default: out += c;
        }
    }
    return out;
}

// The kernel's high-water mark lags behind the resident set that the stages' monitor samples
// (per-thread counters are folded in lazily): the larger of the two.
std::uint64_t peakResidentBytes(const RunReport& report) {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    std::uint64_t peak = std::uint64_t(usage.ru_maxrss) * 1024;  // Linux reports KiB
    for (const StageRecord& s : report.stages) peak = std::max(peak, s.peakMemoryBytes);
    return peak;
}

std::string relativeName(const std::filesystem::path& path, const std::filesystem::path& root) {
    return std::filesystem::relative(path, root).generic_string();
}

// Reference time at the texel render's error, from the reference renders' (error, time)
// points: log-log interpolation between the two that bracket it. Outside their range the answer
// is a bound: "at least" the best reference's time when the texel render beats every reference,
// "at most" the cheapest one's when it is worse than all of them.
struct EqualErrorTime {
    double seconds = 0;
    std::string bound;  // "interpolated", "at least", "at most"
};

std::optional<EqualErrorTime> referenceTimeAtError(std::vector<std::pair<double, double>> points, double rmse) {
    std::erase_if(points, [](const auto& p) { return !(p.first > 0) || !(p.second > 0); });
    if (points.empty() || !(rmse > 0)) return std::nullopt;
    std::sort(points.begin(), points.end());  // by error
    if (rmse <= points.front().first) return EqualErrorTime{points.front().second, "at least"};
    if (rmse >= points.back().first) return EqualErrorTime{points.back().second, "at most"};
    for (std::size_t i = 1; i < points.size(); ++i) {
        const auto& [e0, t0] = points[i - 1];
        const auto& [e1, t1] = points[i];
        if (rmse > e1) continue;
        const double w = e1 > e0 ? std::log(rmse / e0) / std::log(e1 / e0) : 0;
        return EqualErrorTime{std::exp(std::log(t0) + w * std::log(t1 / t0)), "interpolated"};
    }
    return std::nullopt;
}

const RenderStep* findRender(const Pipeline& pipeline, const std::string& name) {
    for (const RenderStep& r : pipeline.renders)
        if (r.name == name) return &r;
    return nullptr;
}

// One table per truth (the `b` of comparisons): every render compared with it, its time (render
// and loading) and its error, and for texel renders the speed-up over the reference of equal error.
Json errorAgainstTime(const Pipeline& pipeline, const RunReport& report) {
    std::map<std::string, Json> renderDetails;
    for (const StageRecord& s : report.stages)
        if (s.kind == "render" && !s.detailsJson.empty()) renderDetails[s.name] = Json::parse(s.detailsJson);
    std::map<std::string, Json> groups;
    for (const StageRecord& s : report.stages) {
        if (s.kind != "compare" || s.detailsJson.empty()) continue;
        const Json metrics = Json::parse(s.detailsJson);
        const std::string a = metrics.value("a", ""), b = metrics.value("b", "");
        const RenderStep* step = findRender(pipeline, a);
        if (!step || !renderDetails.count(a)) continue;
        const Json& stats = renderDetails[a];
        std::string filters;
        for (const auto& [sceneTexel, texel] : step->texels)
            for (const TexelStep& t : pipeline.texels)
                if (t.name == texel) filters += (filters.empty() ? "" : ",") + t.filter;
        Json row = {{"render", a},
                    {"renderer", step->renderer},
                    {"spp", stats.value("spp", step->spp)},
                    {"lod_bias", step->renderer == "texel" ? Json(step->lodBias) : Json(nullptr)},
                    {"shading", step->renderer == "texel" ? Json(step->shading) : Json(nullptr)},
                    {"mode", step->renderer == "reference" ? Json(step->mode) : Json(nullptr)},
                    {"filter", step->renderer == "texel" ? Json(filters) : Json(nullptr)},
                    {"seconds", stats.value("wall_seconds", 0.0) + stats.value("load_seconds", 0.0)},
                    {"rmse", metrics.value("rmse", 0.0)},
                    {"psnr", metrics.value("psnr", Json(nullptr))},
                    {"ssim", metrics.value("ssim", 0.0)}};
        Json& group = groups[b];
        if (group.is_null()) {
            group = {{"truth", b}, {"rows", Json::array()}};
            if (renderDetails.count(b))
                group["truth_seconds"] = renderDetails[b].value("wall_seconds", 0.0) + renderDetails[b].value("load_seconds", 0.0);
        }
        group["rows"].push_back(row);
    }
    Json out = Json::array();
    for (auto& [truth, group] : groups) {
        std::vector<std::pair<double, double>> reference;
        for (const Json& row : group["rows"])
            if (row["renderer"] == "reference") reference.emplace_back(row["rmse"].get<double>(), row["seconds"].get<double>());
        for (Json& row : group["rows"]) {
            if (row["renderer"] != "texel") continue;
            const auto equal = referenceTimeAtError(reference, row["rmse"].get<double>());
            const double seconds = row["seconds"].get<double>();
            if (equal && seconds > 0)
                row["speedup_at_equal_error"] = {{"value", equal->seconds / seconds}, {"bound", equal->bound}};
        }
        out.push_back(group);
    }
    return out;
}

std::string formatNumber(double value, int digits = 3) {
    std::ostringstream s;
    s.precision(digits);
    s << value;
    return s.str();
}

// A log-log scatter of error against time, self-contained SVG.
std::string errorTimePlot(const Json& group) {
    constexpr double W = 560, H = 360, left = 70, right = 20, top = 20, bottom = 50;
    double tMin = INFINITY, tMax = -INFINITY, eMin = INFINITY, eMax = -INFINITY;
    for (const Json& row : group["rows"]) {
        const double t = row["seconds"].get<double>(), e = row["rmse"].get<double>();
        if (!(t > 0) || !(e > 0)) continue;
        tMin = std::min(tMin, t), tMax = std::max(tMax, t), eMin = std::min(eMin, e), eMax = std::max(eMax, e);
    }
    if (!std::isfinite(tMin)) return "";
    const double x0 = std::floor(std::log10(tMin)), x1 = std::max(x0 + 1, std::ceil(std::log10(tMax)));
    const double y0 = std::floor(std::log10(eMin)), y1 = std::max(y0 + 1, std::ceil(std::log10(eMax)));
    auto px = [&](double t) { return left + (std::log10(t) - x0) / (x1 - x0) * (W - left - right); };
    auto py = [&](double e) { return H - bottom - (std::log10(e) - y0) / (y1 - y0) * (H - top - bottom); };
    std::ostringstream svg;
    svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
        << "\" font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    for (double d = x0; d <= x1; ++d)
        svg << "<line x1=\"" << px(std::pow(10, d)) << "\" x2=\"" << px(std::pow(10, d)) << "\" y1=\"" << top << "\" y2=\""
            << H - bottom << "\" stroke=\"#ddd\"/><text x=\"" << px(std::pow(10, d)) << "\" y=\"" << H - bottom + 15
            << "\" text-anchor=\"middle\">" << formatNumber(std::pow(10, d)) << "</text>\n";
    for (double d = y0; d <= y1; ++d)
        svg << "<line x1=\"" << left << "\" x2=\"" << W - right << "\" y1=\"" << py(std::pow(10, d)) << "\" y2=\""
            << py(std::pow(10, d)) << "\" stroke=\"#ddd\"/><text x=\"" << left - 5 << "\" y=\"" << py(std::pow(10, d)) + 4
            << "\" text-anchor=\"end\">" << formatNumber(std::pow(10, d)) << "</text>\n";
    svg << "<text x=\"" << (left + W - right) / 2 << "\" y=\"" << H - 12
        << "\" text-anchor=\"middle\">time to image (s, render + loading)</text>\n<text transform=\"translate(16,"
        << (top + H - bottom) / 2 << ") rotate(-90)\" text-anchor=\"middle\">RMSE against " << escapeHtml(group["truth"])
        << "</text>\n";
    std::vector<std::pair<double, double>> reference;
    for (const Json& row : group["rows"])
        if (row["renderer"] == "reference") reference.emplace_back(row["seconds"].get<double>(), row["rmse"].get<double>());
    std::sort(reference.begin(), reference.end());
    if (reference.size() > 1) {
        svg << "<polyline fill=\"none\" stroke=\"#d95f02\" points=\"";
        for (const auto& [t, e] : reference)
            if (t > 0 && e > 0) svg << px(t) << "," << py(e) << " ";
        svg << "\"/>\n";
    }
    for (const Json& row : group["rows"]) {
        const double t = row["seconds"].get<double>(), e = row["rmse"].get<double>();
        if (!(t > 0) || !(e > 0)) continue;
        const bool isTexel = row["renderer"] == "texel";
        svg << (isTexel ? "<circle r=\"4\" fill=\"#1b9e77\" cx=\"" : "<rect width=\"8\" height=\"8\" fill=\"#d95f02\" x=\"")
            << (isTexel ? px(t) : px(t) - 4) << (isTexel ? "\" cy=\"" : "\" y=\"") << (isTexel ? py(e) : py(e) - 4)
            << "\"><title>" << escapeHtml(row["render"]) << ": " << formatNumber(t) << " s, RMSE " << formatNumber(e)
            << "</title></" << (isTexel ? "circle" : "rect") << ">\n";
    }
    svg << "<circle r=\"4\" fill=\"#1b9e77\" cx=\"" << W - right - 120 << "\" cy=\"" << top + 10
        << "\"/><text x=\"" << W - right - 110 << "\" y=\"" << top + 14 << "\">texel renders</text>\n<rect width=\"8\" "
        << "height=\"8\" fill=\"#d95f02\" x=\"" << W - right - 124 << "\" y=\"" << top + 22 << "\"/><text x=\""
        << W - right - 110 << "\" y=\"" << top + 30 << "\">reference renders</text>\n</svg>\n";
    return svg.str();
}

}  // namespace

void writeReports(const Pipeline& pipeline, RunReport& report) {
    const Json errorTable = errorAgainstTime(pipeline, report);
    report.errorAgainstTimeJson = errorTable.dump();
    Json stages = Json::array();
    for (const StageRecord& s : report.stages) {
        Json outputs = Json::array();
        for (const auto& o : s.outputs) outputs.push_back(relativeName(o, report.output));
        stages.push_back({{"kind", s.kind},
                          {"name", s.name},
                          {"status", statusName(s.status)},
                          {"message", s.message},
                          {"key", s.key},
                          {"seconds", s.seconds},
                          {"peak_memory_bytes", s.peakMemoryBytes},
                          {"outputs", outputs},
                          {"details", s.detailsJson.empty() ? Json::object() : Json::parse(s.detailsJson)}});
    }
    const Json json = {{"vtex_version", kVersion},
                       {"pipeline", pipeline.file.string()},
                       {"succeeded", report.succeeded()},
                       {"seconds", report.seconds},
                       {"peak_memory_bytes", peakResidentBytes(report)},
                       {"stages", stages},
                       {"error_against_time", errorTable},
                       {"left_out", [&] {
                            Json out = Json::array();
                            for (const Omission& o : report.leftOut) out.push_back({{"texel", o.texel}, {"reason", o.reason}});
                            return out;
                        }()}};
    report.reportJson = report.output / "report.json";
    writeFileAtomically(report.reportJson, json.dump(2) + "\n");

    std::ostringstream html;
    html << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>vtex run: "
         << escapeHtml(pipeline.file.filename().string())
         << "</title>\n<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
            "td,th{border:1px solid #bbb;padding:.3em .6em;text-align:left}td.n{text-align:right}"
            ".failed{color:#b00}.skipped{color:#888}img{max-width:480px;margin:.5em}</style></head><body>\n"
         << "<h1>vtex run: " << escapeHtml(pipeline.file.filename().string()) << "</h1>\n<p>vtex " << kVersion
         << ", " << (report.succeeded() ? "all stages succeeded" : "<b class=\"failed\">some stages failed</b>")
         << ", " << report.seconds << " s, peak memory " << peakResidentBytes(report) / (1 << 20) << " MiB.</p>\n"
         << "<h2>Stages</h2>\n<table><tr><th>stage</th><th>name</th><th>status</th><th>seconds</th>"
            "<th>peak MiB</th><th>figures</th></tr>\n";
    for (const StageRecord& s : report.stages) {
        html << "<tr class=\"" << statusName(s.status) << "\"><td>" << s.kind << "</td><td>" << escapeHtml(s.name)
             << "</td><td>" << statusName(s.status) << (s.message.empty() ? "" : ": " + escapeHtml(s.message))
             << "</td><td class=\"n\">" << s.seconds << "</td><td class=\"n\">"
             << (s.peakMemoryBytes ? formatNumber(double(s.peakMemoryBytes) / double(1 << 20)) : std::string("–"))
             << "</td><td><code>"
             << escapeHtml(s.detailsJson.size() > 300 ? s.detailsJson.substr(0, 300) + "…" : s.detailsJson)
             << "</code></td></tr>\n";
    }
    html << "</table>\n";
    if (!report.leftOut.empty()) {
        html << "<h2>Left out (not needed by any render)</h2>\n<ul>\n";
        for (const Omission& o : report.leftOut)
            html << "<li><b>" << escapeHtml(o.texel) << "</b>: " << escapeHtml(o.reason) << "</li>\n";
        html << "</ul>\n";
    }
    if (!errorTable.empty()) {
        html << "<h2>Error against run time</h2>\n<p>Each render measured against the render named as the truth "
                "(the <code>b</code> of its comparison); time is render plus loading, from its stats. The speed-up "
                "of a texel render is the reference's time at the same error (interpolated log-log between "
                "reference renders, or a bound beyond them) over the texel render's time.</p>\n";
        for (const Json& group : errorTable) {
            html << "<h3>Against " << escapeHtml(group["truth"]) << "</h3>\n" << errorTimePlot(group)
                 << "<table><tr><th>render</th><th>renderer</th><th>spp</th><th>lod bias</th><th>shading</th>"
                    "<th>filter</th><th>seconds</th><th>RMSE</th><th>PSNR</th><th>SSIM</th><th>speed-up at equal "
                    "error</th></tr>\n";
            for (const Json& row : group["rows"]) {
                auto cell = [](const Json& v) { return v.is_null() ? std::string("–") : v.is_string() ? v.get<std::string>() : v.dump(); };
                std::string speedup = "–";
                if (row.contains("speedup_at_equal_error")) {
                    const Json& sp = row["speedup_at_equal_error"];
                    speedup = (sp["bound"] == "interpolated" ? "" : sp["bound"].get<std::string>() + " ") + "×" +
                              formatNumber(sp["value"].get<double>());
                }
                html << "<tr><td>" << escapeHtml(row["render"]) << "</td><td>" << cell(row["renderer"])
                     << (row["mode"].is_null() ? "" : " (" + cell(row["mode"]) + ")") << "</td><td class=\"n\">"
                     << cell(row["spp"]) << "</td><td class=\"n\">" << cell(row["lod_bias"]) << "</td><td>"
                     << cell(row["shading"]) << "</td><td>" << cell(row["filter"]) << "</td><td class=\"n\">"
                     << formatNumber(row["seconds"].get<double>()) << "</td><td class=\"n\">"
                     << formatNumber(row["rmse"].get<double>(), 4) << "</td><td class=\"n\">"
                     << (row["psnr"].is_null() ? "∞" : formatNumber(row["psnr"].get<double>(), 4)) << "</td><td class=\"n\">"
                     << formatNumber(row["ssim"].get<double>(), 4) << "</td><td class=\"n\">" << speedup << "</td></tr>\n";
            }
            html << "</table>\n";
        }
    }
    html << "<h2>Images</h2>\n";
    for (const StageRecord& s : report.stages) {
        if (s.status != StageRecord::Status::Ran && s.status != StageRecord::Status::Cached) continue;
        for (const auto& o : s.outputs)
            if (o.extension() == ".png")
                html << "<figure style=\"display:inline-block\"><img src=\"" << escapeHtml(relativeName(o, report.output))
                     << "\"><figcaption>" << s.kind << " " << escapeHtml(s.name) << "</figcaption></figure>\n";
    }
    html << "</body></html>\n";
    report.reportHtml = report.output / "report.html";
    writeFileAtomically(report.reportHtml, html.str());
}

}  // namespace vtex::pipelines
