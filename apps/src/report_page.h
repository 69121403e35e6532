#pragma once
/// \file
/// The data and the HTML of `skerry report` (docs/report.md): one self-contained page with
/// Chart.js, the page's own CSS and JS, and the data inlined.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace skerry::cli {

/// Reads run folders (states.csv, summary.json, ...) and compare folders (table.json, ...)
/// into the page's data. Series are thinned to at most `max_points` points (the solver-time
/// series keeps the maximum of each bucket, so spikes stay visible). Throws InputError for a
/// folder that is neither.
nlohmann::json ReportData(const std::vector<std::string>& dirs, int max_points = 4000);

/// The page: the template with Chart.js, CSS, JS and `data` inlined.
std::string RenderReportHtml(const nlohmann::json& data);

}  // namespace skerry::cli
