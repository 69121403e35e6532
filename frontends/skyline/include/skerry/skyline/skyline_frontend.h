#pragma once
/// \file
/// The skyline frontend of one camera: frames in, one measurement block per usable frame out
/// (solvers/sensor_block.h), the skyline's residual against the horizon re-predicted at the
/// current estimate (skyline_residual.h) on the keyframe's pose with the camera's extrinsic
/// T_b_c. Frames it cannot use (no sky, too few samples) are skipped and counted, never an
/// error; an image of the wrong size is an std::invalid_argument naming both sizes.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skerry/core/sensor_config.h"
#include "skerry/core/time.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/sensor_block.h"
#include "skerry/skyline/camera_model.h"
#include "skerry/skyline/horizon_predictor.h"
#include "skerry/skyline/skyline_residual.h"

namespace skerry::skyline {

/// What happened to a camera's frames.
struct SkylineFrameStats {
  int frames = 0;
  int measurements = 0;           ///< blocks handed over
  int skipped_no_sky = 0;         ///< no skyline found in the image
  int skipped_few_samples = 0;    ///< fewer than min_samples usable samples
  double extraction_s = 0.0;      ///< time spent extracting skylines (read + extract)
};

/// The options of a camera's blocks when the configuration does not name the camera: no loss on
/// the whole block (its samples carry their own Huber; a whole-frame loss would scale a frame of
/// 240 samples as one outlier), the chi-square gate on.
SensorOptions DefaultCameraSensorOptions();

class SkylineFrontend {
 public:
  SkylineFrontend(const CameraConfig& camera, std::shared_ptr<const HorizonPredictor> horizon,
                  const SensorOptions& sensor, const SkylineConfig& config);

  SensorSpec Spec() const;
  template <typename Estimator>
  void Register(Estimator* estimator) {
    id_ = estimator->RegisterSensor(Spec());
  }
  SensorId id() const { return id_; }

  /// The block of one frame from its skyline samples; nullopt (counted) when too few.
  std::optional<SensorMeasurement> Measurement(TimeNs t_ns,
                                               const std::vector<SkylineSample>& samples);

  const CameraModel& camera() const { return camera_; }
  const SkylineConfig& config() const { return config_; }
  SkylineResidualOptions residual_options() const;
  SkylineFrameStats& stats() { return stats_; }
  const SkylineFrameStats& stats() const { return stats_; }
  const std::shared_ptr<const HorizonPredictor>& horizon() const { return horizon_; }

 private:
  CameraModel camera_;
  SensorMount mount_;
  std::string name_;
  std::shared_ptr<const HorizonPredictor> horizon_;
  SensorOptions sensor_;
  SkylineConfig config_;
  SensorId id_ = -1;
  SkylineFrameStats stats_;
};

}  // namespace skerry::skyline
