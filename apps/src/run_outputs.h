#pragma once
/// \file
/// Writing an estimator run to its output folder: trajectory.tum, states.csv, covariances.csv
/// and summary.json.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "skerry/core/dataset.h"
#include "skerry/core/estimate_io.h"
#include "skerry/core/evaluation.h"
#include "skerry/core/gnss_event.h"
#include "skerry/solvers/estimator_config.h"

namespace skerry::cli {

/// Writes the three estimate files into `out_dir` (created).
void WriteEstimateFiles(const std::string& out_dir, const std::vector<EstimateRecord>& records);

/// Dataset facts for summary.json.
nlohmann::json DatasetJson(const Dataset& data);

/// The accuracy figures of one evaluation, with the GNSS-event figures when `events` is not
/// empty.
nlohmann::json AccuracyJson(const EvaluationResult& evaluation,
                            const std::vector<GnssEvent>& events);

/// Accuracy against the dataset's ground truth (null when it has none).
nlohmann::json AccuracyJson(const Dataset& data, const std::vector<EstimateRecord>& records);

/// median / p95 / max of a list.
nlohmann::json DistributionJson(std::vector<double> values);

void WriteJson(const std::string& path, const nlohmann::json& json);

}  // namespace skerry::cli
