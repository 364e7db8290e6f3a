// The pieces report.html is drawn with: numbers as a person reads them, and self-contained SVG
// (a log-log scatter, a horizontal bar chart, a colour bar). No script, no network: the page is
// read as static HTML.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace vtex::pipelines::detail {

std::string escapeHtml(const std::string& text);

/// `value` to `digits` significant digits, fixed notation from 1e-4 to 1e6 ("0.0123", "412"),
/// scientific beyond ("3.1e-07"); "0" for zero.
std::string significant(double value, int digits = 3);

/// A duration as a person reads it: "850 µs", "12.3 ms", "4.56 s", "2 min 05 s".
std::string formatSeconds(double seconds);

/// One point of a scatter plot, in one of the plot's series.
struct PlotPoint {
    double x = 0, y = 0;      ///< data units; points with x ≤ 0 or y ≤ 0 cannot be drawn on log axes
    std::size_t series = 0;   ///< index into the plot's series
    std::string label;        ///< the tooltip (the render's name)
};

struct PlotSeries {
    std::string name;         ///< the legend entry
    std::string colour;       ///< CSS colour
    bool squares = false;     ///< square markers (else discs)
    bool connect = false;     ///< a line through the points from the largest y to the smallest
};

/// A log-log scatter. The legend lists only the series that have a drawable point; empty when no
/// point is drawable.
std::string logLogPlot(const std::vector<PlotPoint>& points, const std::vector<PlotSeries>& series,
                       const std::string& xLabel, const std::string& yLabel);

/// One row of a bar chart: a label and one value per column.
struct BarRow {
    std::string label;
    std::vector<double> values;
};

/// A horizontal bar chart, one block of bars per column (e.g. wall time and peak memory), each
/// column scaled to its own largest value; `format[c]` writes column c's values.
std::string barChart(const std::vector<BarRow>& rows, const std::vector<std::string>& columns,
                     const std::vector<std::string (*)(double)>& format);

/// The heat maps' ramp (render::errorHeatMap: black → red → yellow → white in thirds) as a bar
/// from 0 to `fullScale`, labelled with `what` ("RMS error over R, G, B"); `id` names its
/// gradient, unique in the page.
std::string colourBar(double fullScale, const std::string& what, const std::string& id);

}  // namespace vtex::pipelines::detail
