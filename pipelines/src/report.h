#pragma once

#include <vtex/pipelines/pipeline.h>

#include <nlohmann/json.hpp>

#include <string>

namespace vtex::pipelines {

/// Writes report.json and report.html (self-contained: no network; images by relative path)
/// into report.output, and sets report.reportJson / reportHtml.
void writeReports(const Pipeline& pipeline, RunReport& report);

namespace detail {
/// report.html's text (report_html.cpp): `errorTable` is report.json's `error_against_time`.
std::string htmlPage(const Pipeline& pipeline, const RunReport& report, const nlohmann::json& errorTable);
}  // namespace detail

}  // namespace vtex::pipelines
