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
        const bool texel = step->renderer == Renderer::Texel;
        std::string filters;
        for (const auto& [sceneTexel, texel] : step->texels)
            for (const TexelStep& t : pipeline.texels)
                if (t.name == texel) (filters += filters.empty() ? "" : ",") += octree::kFilterRuleNames.name(t.filter);
        Json row = {{"render", a},
                    {"compare", s.name},
                    {"renderer", kRendererNames.name(step->renderer)},
                    {"spp", stats.value("spp", step->spp)},
                    {"lod_bias", texel ? Json(step->lodBias) : Json(nullptr)},
                    {"shading", texel ? Json(render::kShadingModeNames.name(step->shading)) : Json(nullptr)},
                    {"mode", texel ? Json(nullptr) : Json(render::kReferenceModeNames.name(step->mode))},
                    {"filter", texel ? Json(filters) : Json(nullptr)},
                    {"seconds", stats.value("wall_seconds", 0.0) + stats.value("load_seconds", 0.0)},
                    {"rmse", metrics.value("rmse", 0.0)},
                    {"psnr", metrics.value("psnr", Json(nullptr))},
                    {"ssim", metrics.value("ssim", 0.0)},
                    {"heatmap_scale", metrics.value("heatmap_scale", Json(nullptr))}};
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

    report.reportHtml = report.output / "report.html";
    writeFileAtomically(report.reportHtml, detail::htmlPage(pipeline, report, errorTable));
}

}  // namespace vtex::pipelines
