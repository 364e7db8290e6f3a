#include "report_svg.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace vtex::pipelines::detail {

std::string escapeHtml(const std::string& text) {
    std::string out;
    out.reserve(text.size());
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

std::string significant(double value, int digits) {
    if (value == 0) return "0";
    if (!std::isfinite(value)) return value > 0 ? "∞" : value < 0 ? "−∞" : "–";
    char text[64];
    const int magnitude = int(std::floor(std::log10(std::abs(value))));
    if (magnitude >= -4 && magnitude < 6)
        std::snprintf(text, sizeof text, "%.*f", std::max(0, digits - 1 - magnitude), value);
    else
        std::snprintf(text, sizeof text, "%.*e", std::max(0, digits - 1), value);
    return text;
}

std::string formatSeconds(double seconds) {
    if (!(seconds >= 0) || !std::isfinite(seconds)) return "–";
    if (seconds == 0) return "0 s";
    if (seconds < 1e-3) return significant(seconds * 1e6) + " µs";
    if (seconds < 1) return significant(seconds * 1e3) + " ms";
    if (seconds < 60) return significant(seconds) + " s";
    char text[64];
    const long whole = std::lround(seconds);
    std::snprintf(text, sizeof text, "%ld min %02ld s", whole / 60, whole % 60);
    return text;
}

namespace {

// Decades [lo, hi] covering the values, at least one wide.
std::pair<double, double> decades(double least, double most) {
    const double lo = std::floor(std::log10(least));
    return {lo, std::max(lo + 1, std::ceil(std::log10(most)))};
}

std::string marker(const PlotSeries& s, double x, double y, const std::string& title) {
    std::ostringstream m;
    if (s.squares)
        m << "<rect width=\"8\" height=\"8\" x=\"" << x - 4 << "\" y=\"" << y - 4 << "\" fill=\"" << s.colour << "\">";
    else
        m << "<circle r=\"4.5\" cx=\"" << x << "\" cy=\"" << y << "\" fill=\"" << s.colour << "\">";
    if (!title.empty()) m << "<title>" << escapeHtml(title) << "</title>";
    m << (s.squares ? "</rect>" : "</circle>") << "\n";
    return m.str();
}

}  // namespace

std::string logLogPlot(const std::vector<PlotPoint>& points, const std::vector<PlotSeries>& series,
                       const std::string& xLabel, const std::string& yLabel) {
    constexpr double W = 560, H = 340, left = 64, right = 16, top = 14, bottom = 46;
    std::vector<PlotPoint> drawn;
    for (const PlotPoint& p : points)
        if (p.x > 0 && p.y > 0 && std::isfinite(p.x) && std::isfinite(p.y) && p.series < series.size()) drawn.push_back(p);
    if (drawn.empty()) return "";
    const auto [xMin, xMax] = std::minmax_element(drawn.begin(), drawn.end(), [](auto& a, auto& b) { return a.x < b.x; });
    const auto [yMin, yMax] = std::minmax_element(drawn.begin(), drawn.end(), [](auto& a, auto& b) { return a.y < b.y; });
    const auto [x0, x1] = decades(xMin->x, xMax->x);
    const auto [y0, y1] = decades(yMin->y, yMax->y);
    auto px = [&](double x) { return left + (std::log10(x) - x0) / (x1 - x0) * (W - left - right); };
    auto py = [&](double y) { return H - bottom - (std::log10(y) - y0) / (y1 - y0) * (H - top - bottom); };

    std::ostringstream svg;
    svg << "<svg class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " << W << " " << H << "\" width=\"" << W
        << "\" height=\"" << H << "\" font-family=\"sans-serif\" font-size=\"11\">\n"
        << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    // Grid lines and labels at every decade.
    for (double d = x0; d <= x1; ++d)
        svg << "<line x1=\"" << px(std::pow(10, d)) << "\" x2=\"" << px(std::pow(10, d)) << "\" y1=\"" << top << "\" y2=\""
            << H - bottom << "\" stroke=\"#ddd\"/><text x=\"" << px(std::pow(10, d)) << "\" y=\"" << H - bottom + 15
            << "\" text-anchor=\"middle\">" << significant(std::pow(10, d), 1) << "</text>\n";
    for (double d = y0; d <= y1; ++d)
        svg << "<line x1=\"" << left << "\" x2=\"" << W - right << "\" y1=\"" << py(std::pow(10, d)) << "\" y2=\""
            << py(std::pow(10, d)) << "\" stroke=\"#ddd\"/><text x=\"" << left - 5 << "\" y=\"" << py(std::pow(10, d)) + 4
            << "\" text-anchor=\"end\">" << significant(std::pow(10, d), 1) << "</text>\n";
    svg << "<text x=\"" << (left + W - right) / 2 << "\" y=\"" << H - 10 << "\" text-anchor=\"middle\">" << escapeHtml(xLabel)
        << "</text>\n<text transform=\"translate(14," << (top + H - bottom) / 2
        << ") rotate(-90)\" text-anchor=\"middle\">" << escapeHtml(yLabel) << "</text>\n";

    // Lines first (under the markers), then the markers, then the legend of the drawn series.
    std::vector<bool> present(series.size(), false);
    for (const PlotPoint& p : drawn) present[p.series] = true;
    for (std::size_t s = 0; s < series.size(); ++s) {
        std::vector<std::pair<double, double>> line;
        for (const PlotPoint& p : drawn)
            if (p.series == s) line.emplace_back(p.x, p.y);
        if (!series[s].connect || line.size() < 2) continue;
        // By y, not x: reference renders' errors fall with spp, while their times (of a few
        // milliseconds at 1 and 4 spp) may come in either order.
        std::sort(line.begin(), line.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
        svg << "<polyline fill=\"none\" stroke=\"" << series[s].colour << "\" points=\"";
        for (const auto& [x, y] : line) svg << px(x) << "," << py(y) << " ";
        svg << "\"/>\n";
    }
    for (const PlotPoint& p : drawn) svg << marker(series[p.series], px(p.x), py(p.y), p.label);
    double legendY = top + 10;
    for (std::size_t s = 0; s < series.size(); ++s) {
        if (!present[s]) continue;
        svg << marker(series[s], W - right - 150, legendY, "") << "<text x=\"" << W - right - 140 << "\" y=\"" << legendY + 4
            << "\">" << escapeHtml(series[s].name) << "</text>\n";
        legendY += 16;
    }
    svg << "</svg>\n";
    return svg.str();
}

std::string barChart(const std::vector<BarRow>& rows, const std::vector<std::string>& columns,
                     const std::vector<std::string (*)(double)>& format) {
    if (rows.empty() || columns.empty()) return "";
    constexpr double labelWidth = 320, columnWidth = 270, gap = 24, rowHeight = 16, top = 22;
    const double W = labelWidth + double(columns.size()) * (columnWidth + gap);
    const double H = top + double(rows.size()) * rowHeight + 6;
    std::vector<double> largest(columns.size(), 0);
    for (const BarRow& r : rows)
        for (std::size_t c = 0; c < columns.size() && c < r.values.size(); ++c) largest[c] = std::max(largest[c], r.values[c]);
    static const char* colours[] = {"#4c78a8", "#f58518", "#54a24b"};
    std::ostringstream svg;
    svg << "<svg class=\"bars\" xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " << W << " " << H << "\" width=\"" << W
        << "\" height=\"" << H << "\" font-family=\"sans-serif\" font-size=\"11\">\n";
    for (std::size_t c = 0; c < columns.size(); ++c)
        svg << "<text x=\"" << labelWidth + double(c) * (columnWidth + gap) << "\" y=\"14\" font-weight=\"bold\">"
            << escapeHtml(columns[c]) << "</text>\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const double y = top + double(i) * rowHeight;
        svg << "<text x=\"" << labelWidth - 6 << "\" y=\"" << y + 11 << "\" text-anchor=\"end\">" << escapeHtml(rows[i].label)
            << "</text>\n";
        for (std::size_t c = 0; c < columns.size() && c < rows[i].values.size(); ++c) {
            const double v = rows[i].values[c];
            // The bar leaves room for its value written after it.
            const double w = largest[c] > 0 ? std::max(0.0, v) / largest[c] * (columnWidth - 70) : 0;
            const double x = labelWidth + double(c) * (columnWidth + gap);
            svg << "<rect x=\"" << x << "\" y=\"" << y + 2 << "\" width=\"" << w << "\" height=\"" << rowHeight - 4
                << "\" fill=\"" << colours[c % 3] << "\"/><text x=\"" << x + w + 4 << "\" y=\"" << y + 11 << "\">"
                << escapeHtml(format[c](v)) << "</text>\n";
        }
    }
    svg << "</svg>\n";
    return svg.str();
}

std::string colourBar(double fullScale, const std::string& what, const std::string& id) {
    constexpr double W = 320, barLeft = 10, barWidth = 300;
    std::ostringstream svg;
    svg << "<svg class=\"colourbar\" xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " << W << " 46\" width=\"" << W
        << "\" height=\"46\" font-family=\"sans-serif\" font-size=\"11\">\n"
        << "<defs><linearGradient id=\"" << id << "\" x1=\"0\" x2=\"1\" y1=\"0\" y2=\"0\">"
           "<stop offset=\"0\" stop-color=\"#000\"/><stop offset=\"0.3333\" stop-color=\"#f00\"/>"
           "<stop offset=\"0.6667\" stop-color=\"#ff0\"/><stop offset=\"1\" stop-color=\"#fff\"/></linearGradient></defs>\n"
        << "<rect x=\"" << barLeft << "\" y=\"4\" width=\"" << barWidth << "\" height=\"14\" fill=\"url(#" << id << ")\" "
        << "stroke=\"#888\"/>\n";
    for (int i = 0; i <= 4; ++i) {
        const double x = barLeft + barWidth * i / 4.0;
        svg << "<line x1=\"" << x << "\" x2=\"" << x << "\" y1=\"18\" y2=\"22\" stroke=\"#444\"/><text x=\"" << x
            << "\" y=\"32\" text-anchor=\"" << (i == 0 ? "start" : i == 4 ? "end" : "middle") << "\">"
            << (i == 4 ? "≥ " : "") << significant(fullScale * i / 4.0, 2) << "</text>\n";
    }
    svg << "<text x=\"" << barLeft + barWidth / 2 << "\" y=\"44\" text-anchor=\"middle\">" << escapeHtml(what) << "</text>\n"
        << "</svg>\n";
    return svg.str();
}

}  // namespace vtex::pipelines::detail
