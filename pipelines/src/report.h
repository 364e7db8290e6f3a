#pragma once

#include <vtex/pipelines/pipeline.h>

namespace vtex::pipelines {

/// Writes report.json and report.html (self-contained: no network; images by relative path)
/// into report.output, and sets report.reportJson / reportHtml.
void writeReports(const Pipeline& pipeline, RunReport& report);

}  // namespace vtex::pipelines
