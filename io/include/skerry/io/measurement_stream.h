#pragma once
/// \file
/// A recording's IMU samples and GNSS fixes, one at a time, each in time order: from a dataset in
/// memory, or read from its files as they are needed, so that a run over a day of 200 Hz data
/// holds a few rows of it and not 17 million (RunWindow takes either).

#include <cstdint>
#include <optional>
#include <string>

#include "skerry/core/geodesy.h"
#include "skerry/core/measurements.h"
#include "skerry/io/csv_reader.h"
#include "skerry/io/dataset.h"

namespace skerry {

class MeasurementStream {
 public:
  virtual ~MeasurementStream() = default;
  /// The next sample / fix in time order; false at the end. Throws InputError on a bad row.
  virtual bool NextImu(ImuSample* sample) = 0;
  virtual bool NextGnss(GnssFix* fix) = 0;
  /// How much of the recording has been read, in [0, 1] (for progress).
  virtual double Fraction() = 0;
};

/// Over a dataset loaded whole (it must outlive the stream).
class InMemoryStream : public MeasurementStream {
 public:
  explicit InMemoryStream(const Dataset& data) : data_(data) {}
  bool NextImu(ImuSample* sample) override;
  bool NextGnss(GnssFix* fix) override;
  double Fraction() override;

 private:
  const Dataset& data_;
  size_t imu_ = 0;
  size_t gnss_ = 0;
};

/// Over the imu.csv and gnss.csv of a dataset loaded with DatasetParts::kWithoutStreams, read a
/// row at a time with the checks LoadDataset makes (InputError naming file, line and column, as
/// the rows come).
class DatasetFileStream : public MeasurementStream {
 public:
  explicit DatasetFileStream(const Dataset& header);
  bool NextImu(ImuSample* sample) override;
  bool NextGnss(GnssFix* fix) override;
  double Fraction() override;

 private:
  std::string imu_path_;
  CsvReader imu_;
  std::optional<CsvReader> gnss_;
  LocalFrame frame_;
  std::int64_t imu_bytes_ = 0;  ///< imu.csv's size
  bool any_imu_ = false;
};

}  // namespace skerry
