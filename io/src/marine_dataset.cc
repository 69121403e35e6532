#include "skerry/io/marine_dataset.h"

#include <cmath>
#include <filesystem>

#include "skerry/core/input_error.h"

namespace skerry {
namespace {

// The log's file name without its extensions (furuno.si.jsonl.gz -> furuno).
std::string NameOf(const std::string& path) {
  std::filesystem::path p = std::filesystem::path(path).filename();
  static const char* const kExtensions[] = {".gz",  ".jsonl", ".json", ".si", ".nmea",
                                            ".log", ".txt",   ".csv",  ".n2k"};
  bool stripped = true;
  while (stripped) {
    stripped = false;
    for (const char* ext : kExtensions) {
      if (p.extension() == ext && !p.stem().empty()) {
        p = p.stem();
        stripped = true;
      }
    }
  }
  return p.string();
}

// Keeps the records of one source (the chosen or the busiest) and one record per time.
template <typename Record>
std::vector<Record> Select(const std::vector<Record>& records,
                           MarineKind kind,
                           const MarineDatasetOptions& options,
                           const std::string& log_path,
                           MarineKindSelection* sel) {
  for (const Record& r : records) ++sel->records_by_source[r.source];
  const auto wanted = options.sources.find(kind);
  if (wanted != options.sources.end()) {
    if (sel->records_by_source.count(wanted->second) == 0) {
      throw InputError(log_path, 0, MarineKindName(kind),
                       "no " + std::string(MarineKindName(kind)) + " record from source \"" +
                           wanted->second + "\"");
    }
    sel->source = wanted->second;
  } else {
    int most = 0;
    for (const auto& [source, n] : sel->records_by_source) {
      if (n > most) {  // map order: ties keep the smallest name
        most = n;
        sel->source = source;
      }
    }
  }
  std::vector<Record> kept;
  for (const Record& r : records) {
    if (r.source != sel->source) {
      ++sel->other_sources;
    } else if (!kept.empty() && r.t_ns <= kept.back().t_ns) {
      ++sel->duplicates;  // the readers drop earlier times, so this is the same time
    } else {
      kept.push_back(r);
    }
  }
  sel->kept = static_cast<int>(kept.size());
  return kept;
}

}  // namespace

const char* MarineKindName(MarineKind kind) {
  switch (kind) {
    case MarineKind::kFix:
      return "fix";
    case MarineKind::kHeading:
      return "heading";
    case MarineKind::kCourse:
      return "course";
    case MarineKind::kAttitude:
      return "attitude";
    case MarineKind::kRateOfTurn:
      return "rate_of_turn";
  }
  return "?";
}

bool ParseMarineKind(const std::string& name, MarineKind* kind) {
  for (MarineKind k : {MarineKind::kFix, MarineKind::kHeading, MarineKind::kCourse,
                       MarineKind::kAttitude, MarineKind::kRateOfTurn}) {
    if (name == MarineKindName(k)) {
      *kind = k;
      return true;
    }
  }
  return false;
}

Dataset MarineLogToDataset(const MarineLog& log,
                           const MarineDatasetOptions& options,
                           MarineSelection* selection) {
  MarineSelection local;
  MarineSelection& sel = selection != nullptr ? *selection : local;
  sel.clear();
  const std::vector<MarineFix> fixes =
      Select(log.fixes, MarineKind::kFix, options, log.path, &sel[MarineKind::kFix]);
  if (fixes.empty()) {
    throw InputError(log.path, 0, "",
                     "no valid position fix in the " + log.format + " log (" +
                         std::to_string(log.stats.lines) + " lines, " +
                         std::to_string(log.stats.BadCount()) +
                         " bad: docs/marine_logs.md says which are read)");
  }
  Dataset data;
  data.name = options.name.empty() ? NameOf(log.path) : options.name;
  data.has_imu = false;
  data.has_gnss = true;
  data.gnss.p_b_g = Eigen::Vector3d::Zero();
  data.origin.lat_deg = fixes.front().lat_deg;
  data.origin.lon_deg = fixes.front().lon_deg;
  data.origin.height_m = 0.0;
  for (const MarineFix& f : fixes) {
    if (f.height_m) {
      data.origin.height_m = *f.height_m;
      break;
    }
  }
  const LocalFrame frame(data.origin);
  for (const MarineFix& f : fixes) {
    GnssFix g;
    g.t_ns = f.t_ns;
    g.lat_deg = f.lat_deg;
    g.lon_deg = f.lon_deg;
    g.height_m = f.height_m.value_or(data.origin.height_m);
    g.sigma_enu_m = Eigen::Vector3d(f.sigma_east_m, f.sigma_north_m,
                                    f.height_m ? f.sigma_up_m : kUnknownHeightSigmaM);
    g.p_w = frame.ToEnu(g.lat_deg, g.lon_deg, g.height_m);
    data.gnss_fixes.push_back(g);
  }
  const MarineRecords& r = log.records;
  data.marine.headings =
      Select(r.headings, MarineKind::kHeading, options, log.path, &sel[MarineKind::kHeading]);
  data.marine.courses =
      Select(r.courses, MarineKind::kCourse, options, log.path, &sel[MarineKind::kCourse]);
  data.marine.attitudes =
      Select(r.attitudes, MarineKind::kAttitude, options, log.path, &sel[MarineKind::kAttitude]);
  data.marine.rates_of_turn = Select(r.rates_of_turn, MarineKind::kRateOfTurn, options, log.path,
                                     &sel[MarineKind::kRateOfTurn]);
  return data;
}

TrackFigures FixTrackFigures(const std::vector<GnssFix>& fixes) {
  TrackFigures t;
  t.fixes = static_cast<int>(fixes.size());
  if (fixes.size() < 2) return t;
  t.span_s = NsToSeconds(fixes.back().t_ns - fixes.front().t_ns);
  t.rate_hz = t.span_s > 0.0 ? (fixes.size() - 1) / t.span_s : 0.0;
  for (std::size_t k = 1; k < fixes.size(); ++k) {
    t.length_m += (fixes[k].p_w - fixes[k - 1].p_w).head<2>().norm();
  }
  return t;
}

}  // namespace skerry
