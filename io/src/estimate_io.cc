#include "skerry/io/estimate_io.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include "skerry/core/input_error.h"
#include "skerry/io/atomic_file.h"
#include "skerry/io/csv_reader.h"
#include "skerry/io/state_row_io.h"

namespace skerry {
namespace {

std::vector<std::string> StatesColumns() {
  std::vector<std::string> columns = NavStateColumns();
  for (const char* name : {"sigma_px", "sigma_py", "sigma_pz", "sigma_heading_deg"}) {
    columns.emplace_back(name);
  }
  return columns;
}

// c00, c01, ..., c09, c0_10, ..., c0_14, c11, ...: two-digit names while both indices are single
// digits, an underscore otherwise (so c1_14 cannot be confused with c11 followed by 4).
std::string CovarianceColumnName(int i, int j) {
  if (i < 10 && j < 10) return "c" + std::to_string(i) + std::to_string(j);
  return "c" + std::to_string(i) + "_" + std::to_string(j);
}

std::vector<std::string> CovarianceColumns() {
  std::vector<std::string> columns = {"t"};
  for (int i = 0; i < kStateDim; ++i) {
    for (int j = i; j < kStateDim; ++j) columns.push_back(CovarianceColumnName(i, j));
  }
  return columns;
}

void WriteHeader(std::ofstream* out, const std::vector<std::string>& columns) {
  for (std::size_t i = 0; i < columns.size(); ++i) *out << (i > 0 ? "," : "") << columns[i];
  *out << '\n';
}

}  // namespace

double HeadingSigmaDeg(const StateCovariance& covariance) {
  // The rotation tangent is world-frame, so its z component is a rotation about up: heading.
  return std::sqrt(std::max(0.0, covariance(kRot + 2, kRot + 2))) * 180.0 / M_PI;
}

double HorizontalSigmaM(const StateCovariance& covariance) {
  return std::sqrt(std::max(0.0, covariance.block<2, 2>(kPos, kPos).trace()));
}

EstimateFilesWriter::EstimateFilesWriter(const std::string& out_dir)
    : tum_(out_dir + "/trajectory.tum"),
      states_(out_dir + "/states.csv"),
      covariances_(out_dir + "/covariances.csv") {
  tum_.stream() << kTumHeader;
  WriteHeader(&states_.stream(), StatesColumns());
  WriteHeader(&covariances_.stream(), CovarianceColumns());
}

void EstimateFilesWriter::Append(const std::vector<EstimateRecord>& records) {
  // Each row is made in one string and handed to its file whole: numbers by to_chars
  // (AppendDouble), the text of printf's %.17g, a few times faster than printf.
  std::string tum, states, covariances;
  for (const EstimateRecord& r : records) {
    tum.clear();
    AppendTumRow({r.state.t_ns, r.state.p_w_b, r.state.q_w_b}, &tum);
    tum_.stream() << tum;
    states.clear();
    AppendNavStateRow(r.state, &states);
    if (r.has_covariance) {
      for (int i = 0; i < 3; ++i) {
        states += ',';
        AppendDouble(std::sqrt(std::max(0.0, r.covariance(kPos + i, kPos + i))), &states);
      }
      states += ',';
      AppendDouble(HeadingSigmaDeg(r.covariance), &states);
    } else {
      states += ",,,,";
    }
    states += '\n';
    states_.stream() << states;
    if (!r.has_covariance) continue;
    covariances.clear();
    AppendSeconds(r.state.t_ns, &covariances);
    for (int i = 0; i < kStateDim; ++i) {
      for (int j = i; j < kStateDim; ++j) {
        covariances += ',';
        AppendDouble(r.covariance(i, j), &covariances);
      }
    }
    covariances += '\n';
    covariances_.stream() << covariances;
  }
  count_ += records.size();
}

void EstimateFilesWriter::Commit() {
  // states.csv last: a reader looks for it first.
  tum_.Commit();
  covariances_.Commit();
  states_.Commit();
}

void WriteEstimateFiles(const std::string& out_dir, const std::vector<EstimateRecord>& records) {
  std::filesystem::create_directories(out_dir);
  EstimateFilesWriter writer(out_dir);
  writer.Append(records);
  writer.Commit();
}

std::vector<EstimateRecord> ReadEstimate(const std::string& states_path,
                                         const std::string& covariances_path) {
  std::vector<EstimateRecord> records;
  std::map<TimeNs, std::size_t> index_by_time;
  {
    CsvReader reader(states_path, StatesColumns());
    while (reader.Next()) {
      EstimateRecord record;
      record.state = ReadNavStateRow(&reader);
      // The sigma columns are derived from the covariance file; only check they are numbers.
      for (int col = 17; col < 21; ++col) {
        const std::optional<double> sigma = reader.GetOptionalDouble(col);
        if (sigma && *sigma < 0.0) reader.Fail(col, "sigma must not be negative");
      }
      index_by_time[record.state.t_ns] = records.size();
      records.push_back(record);
    }
  }
  if (covariances_path.empty() || !std::filesystem::exists(covariances_path)) return records;

  CsvReader reader(covariances_path, CovarianceColumns());
  while (reader.Next()) {
    const TimeNs t = reader.GetIncreasingTimeNs(0);
    const auto it = index_by_time.find(t);
    if (it == index_by_time.end()) {
      reader.Fail(0, "no state at time " + FormatSeconds(t) + " in " + states_path);
    }
    EstimateRecord& record = records[it->second];
    int col = 1;
    for (int i = 0; i < kStateDim; ++i) {
      for (int j = i; j < kStateDim; ++j, ++col) {
        const double c = reader.GetDouble(col);
        if (i == j && c < 0.0) reader.Fail(col, "negative variance");
        record.covariance(i, j) = c;
        record.covariance(j, i) = c;
      }
    }
    record.has_covariance = true;
  }
  return records;
}

std::vector<StampedPose> ToPoses(const std::vector<EstimateRecord>& records) {
  std::vector<StampedPose> poses;
  poses.reserve(records.size());
  for (const EstimateRecord& r : records) {
    StampedPose pose;
    pose.t_ns = r.state.t_ns;
    pose.p_w_b = r.state.p_w_b;
    pose.q_w_b = r.state.q_w_b;
    poses.push_back(pose);
  }
  return poses;
}

}  // namespace skerry
