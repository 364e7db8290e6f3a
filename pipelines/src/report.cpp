#include "report.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/version.h>

#include <nlohmann/json.hpp>

#include <sstream>

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

std::uint64_t peakResidentBytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return std::uint64_t(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

std::string relativeName(const std::filesystem::path& path, const std::filesystem::path& root) {
    return std::filesystem::relative(path, root).generic_string();
}

}  // namespace

void writeReports(const Pipeline& pipeline, RunReport& report) {
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
                          {"outputs", outputs},
                          {"details", s.detailsJson.empty() ? Json::object() : Json::parse(s.detailsJson)}});
    }
    const Json json = {{"vtex_version", kVersion},
                       {"pipeline", pipeline.file.string()},
                       {"succeeded", report.succeeded()},
                       {"seconds", report.seconds},
                       {"peak_memory_bytes", peakResidentBytes()},
                       {"stages", stages},
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
         << ", " << report.seconds << " s, peak memory " << peakResidentBytes() / (1 << 20) << " MiB.</p>\n"
         << "<h2>Stages</h2>\n<table><tr><th>stage</th><th>name</th><th>status</th><th>seconds</th>"
            "<th>figures</th></tr>\n";
    for (const StageRecord& s : report.stages) {
        html << "<tr class=\"" << statusName(s.status) << "\"><td>" << s.kind << "</td><td>" << escapeHtml(s.name)
             << "</td><td>" << statusName(s.status) << (s.message.empty() ? "" : ": " + escapeHtml(s.message))
             << "</td><td class=\"n\">" << s.seconds << "</td><td><code>"
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
