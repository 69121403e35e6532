#pragma once
/// \file
/// A twin folder (`skerry twin`, docs/twin.md) as data for `skerry report`: twin.yaml (the
/// identified and calibrated models, the fidelity test against its floor, the GNSS statistics of
/// a log without IMU) and fidelity/over_time.csv (the recording's Hellinger distance to its
/// twins per epoch). The recording's run and a twin's (fidelity/real, fidelity/twin-N) are run
/// folders the report reads as any other.

#include <nlohmann/json.hpp>
#include <string>

namespace skerry::cli {

/// True when `dir` holds a twin.yaml (what `skerry twin` writes last).
bool IsTwinFolder(const std::string& dir);

/// twin.yaml as JSON (maps, sequences; scalars as finite numbers, booleans or strings) under
/// "yaml", the folder under "folder", and over_time.csv thinned to `max_points` under
/// "over_time" ({"t": [...], "twins_valid": [...], "<block>": [...]}, t in s from `t0_s`), or
/// null without one. Throws InputError naming the file and line of a malformed twin.yaml or CSV.
nlohmann::json TwinReportData(const std::string& dir, int max_points, double t0_s);

/// The seed of the first twin run the folder holds (fidelity/twin-N with a states.csv), or -1.
int FirstTwinRunSeed(const std::string& dir);

}  // namespace skerry::cli
