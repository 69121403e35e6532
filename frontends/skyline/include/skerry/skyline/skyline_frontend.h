#pragma once
/// \file
/// The skyline frontend of one camera: frames in, one measurement block per usable frame out
/// (solvers/sensor_block.h), the skyline's residual against the horizon re-predicted at the
/// current estimate (skyline_residual.h) on the keyframe's pose with the camera's extrinsic
/// T_b_c. Frames it cannot use (no sky, too few samples) are skipped and counted, never an
/// error; an image of the wrong size is an std::invalid_argument naming both sizes.

#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "skerry/core/sensor_config.h"
#include "skerry/core/time.h"
#include "skerry/skyline/camera_model.h"
#include "skerry/skyline/frame_locator.h"
#include "skerry/skyline/horizon_predictor.h"
#include "skerry/skyline/skyline_residual.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/sensor_block.h"

namespace skerry::skyline {

/// A frame that became a block, as the window last made it (the run folder's blocks.csv).
struct SkylineFrameFigures {
  int samples = 0;  ///< skyline samples in the block
  /// The share of an independent frame's information it keeps (frame_correlation_s/_m), its
  /// crests' median shift since the frame before (m; NaN for the first frame or without
  /// frame_correlation_m) and its samples' mean map term (px; dem_sigma_m, else 0). The weight
  /// and map term are NaN until the window has made the block.
  double frame_weight = std::numeric_limits<double>::quiet_NaN();
  double crest_shift_m = std::numeric_limits<double>::quiet_NaN();
  double map_sigma_px = std::numeric_limits<double>::quiet_NaN();
};

/// What happened to a camera's frames.
struct SkylineFrameStats {
  int frames = 0;
  int measurements = 0;         ///< blocks handed over
  int skipped_no_sky = 0;       ///< no skyline found in the image
  int skipped_few_samples = 0;  ///< fewer than min_samples usable samples
  int relocations_tried = 0;    ///< global searches after a streak of rejected frames
  int relocations_found = 0;    ///< of which gave an unambiguous pose
  double extraction_s = 0.0;    ///< time spent extracting skylines (read + extract)
  /// skyline.frame_correlation_m or dem_sigma_m: over the frames the window prepared, the sum of
  /// their frame weights and of their crests' median shift since the frame before, and how many had
  /// one.
  double frame_weight_sum = 0.0;
  int weighted_frames = 0;
  double crest_shift_m_sum = 0.0;
  int crest_frames = 0;
  /// skyline.dem_sigma_m: over the same frames, the sum of their samples' mean map term, px
  /// (SkylineResidualModel::AddMapError).
  double map_sigma_px_sum = 0.0;
  /// Per block time, every frame handed over as a block.
  std::map<TimeNs, SkylineFrameFigures> per_frame;
};

/// The options of a camera's blocks when the configuration does not name the camera: no loss on
/// the whole block (its samples carry their own Huber; a whole-frame loss would scale a frame of
/// 240 samples as one outlier), the chi-square gate on.
SensorOptions DefaultCameraSensorOptions();

class SkylineFrontend {
 public:
  SkylineFrontend(const CameraConfig& camera,
                  std::shared_ptr<const HorizonPredictor> horizon,
                  const SensorOptions& sensor,
                  const SkylineConfig& config);

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
  /// What the camera estimates with the states: refraction (skyline.refraction_k_sigma > 0), the
  /// crest offset (crest_offset_sigma_m > 0), the sharpening gain (dem_sharpening_sigma > 0) or
  /// nothing; std::invalid_argument for more than one.
  SkylineParameter EstimatedParameter() const;
  /// Per frame handed over, its figures (SkylineFrameFigures) for the window's blocks.csv.
  FrontendBlockTable BlockTable() const;
  SkylineFrameStats& stats() { return *stats_; }
  const SkylineFrameStats& stats() const { return *stats_; }

  /// The global search around an estimate on the frame of a rejected block (SensorSpec's
  /// relocate: the back end calls it after a streak of rejected frames); nullopt when the search
  /// fails or is ambiguous.
  std::optional<Relocation> Relocate(const SensorMeasurement& rejected,
                                     const NavState& estimate,
                                     const StateCovariance& covariance,
                                     bool after_rejections = true) const;

  /// The body pose from one frame handed over earlier, by the global search within radius_m of
  /// prior_p_w_b, heading unknown, tilt from the body's up direction (the accelerometer's mean
  /// specific force, body frame); nullopt when the search fails or is ambiguous.
  std::optional<Relocation> Locate(TimeNs t_ns,
                                   const Eigen::Vector3d& up_b,
                                   const Eigen::Vector3d& prior_p_w_b,
                                   double radius_m) const;
  /// Times of the frames handed over, in order.
  std::vector<TimeNs> FrameTimes() const;
  const std::shared_ptr<const HorizonPredictor>& horizon() const { return horizon_; }

 private:
  CameraModel camera_;
  SensorMount mount_;
  std::string name_;
  std::shared_ptr<const HorizonPredictor> horizon_;
  SensorOptions sensor_;
  SkylineConfig config_;
  SensorId id_ = -1;
  TimeNs last_frame_ns_ = -1;
  /// Where each consumer's state put the camera at the frames it prepared (the crest's motion is
  /// measured against the frame before, skyline.frame_correlation_m).
  struct CrestHistory {
    std::mutex mutex;
    std::map<BlockConsumer, std::map<TimeNs, Eigen::Vector3d>> camera_positions;
  };
  std::shared_ptr<CrestHistory> crests_ = std::make_shared<CrestHistory>();
  /// Shared with the relocation callback, which outlives a copied frontend.
  std::shared_ptr<SkylineFrameStats> stats_ = std::make_shared<SkylineFrameStats>();
  /// The samples of every frame handed over, by time: what a relocation searches with.
  std::shared_ptr<std::map<TimeNs, std::vector<SkylineSample>>> frames_ =
      std::make_shared<std::map<TimeNs, std::vector<SkylineSample>>>();
};

}  // namespace skerry::skyline
