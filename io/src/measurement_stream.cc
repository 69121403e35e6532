#include "skerry/io/measurement_stream.h"

#include <algorithm>
#include <filesystem>
#include <system_error>

namespace skerry {

bool InMemoryStream::NextImu(ImuSample* sample) {
  if (imu_ >= data_.imu_samples.size()) return false;
  *sample = data_.imu_samples[imu_++];
  return true;
}

bool InMemoryStream::NextGnss(GnssFix* fix) {
  if (gnss_ >= data_.gnss_fixes.size()) return false;
  *fix = data_.gnss_fixes[gnss_++];
  return true;
}

double InMemoryStream::Fraction() {
  return data_.imu_samples.empty() ? 1.0 : static_cast<double>(imu_) / data_.imu_samples.size();
}

DatasetFileStream::DatasetFileStream(const Dataset& header)
    : imu_path_(header.imu_path), imu_(OpenImuCsv(header.imu_path)), frame_(header.origin) {
  if (header.has_gnss) gnss_.emplace(OpenGnssCsv(header.gnss_path));
  std::error_code ec;
  const auto size = std::filesystem::file_size(header.imu_path, ec);
  imu_bytes_ = ec ? 0 : static_cast<std::int64_t>(size);
}

bool DatasetFileStream::NextImu(ImuSample* sample) {
  if (!imu_.Next()) {
    if (!any_imu_) ThrowNoImuSamples(imu_path_);
    return false;
  }
  *sample = ReadImuRow(&imu_);
  any_imu_ = true;
  return true;
}

bool DatasetFileStream::NextGnss(GnssFix* fix) {
  if (!gnss_ || !gnss_->Next()) return false;
  *fix = ReadGnssRow(frame_, &*gnss_);
  return true;
}

double DatasetFileStream::Fraction() {
  const std::int64_t read = imu_.bytes_read();
  if (imu_bytes_ <= 0 || read < 0) return 0.0;
  return std::min(1.0, static_cast<double>(read) / static_cast<double>(imu_bytes_));
}

}  // namespace skerry
