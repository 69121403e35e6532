#pragma once
/// \file
/// The sensor models of a recording, identified from the recording itself against a smooth truth
/// through it (the batch smoother's trajectory, sim/spline_motion.h): what `skerry twin` writes
/// to twin.yaml and simulates its twin with (docs/twin.md).
///
/// - IMU white noise, bias instability and rate random walk from the overlapping Allan deviation
///   of the longest rest period (eval/allan_deviation.h), when there is one of at least
///   `min_rest_s`; the white noise also, always, from the residuals of the measurements against
///   what a perfect IMU senses on the truth less the truth's biases (the spread of their first
///   differences, so that a slowly wrong bias does not count). The residuals hold every motion
///   the truth is too smooth to follow (vibration, the hull's shudder), which an estimator sees as
///   noise too.
/// - GNSS: the fixes' residuals against the truth's antenna, in the local east, north, up. Gross
///   errors first: a fix whose residual lies more than `gross_threshold_sigma` robust scales
///   (1.4826 MAD of all residuals, drift included) from their median, horizontally or
///   vertically; consecutive ones form an episode (a jump, a reflected signal), summarised as a
///   rate, a mean length and the RMS of the episodes' mean offsets. Then latency, white noise and
///   Gauss-Markov drift from the other fixes (eval/gnss_error_model.h).
///   The truth itself holds whatever part of a slow drift the IMU could not tell from motion,
///   so a drift is seen only as far as the fusion rejected it.
/// - Dual-antenna heading noise from its residuals against the truth's baseline heading.
/// - Rates, jitter, gaps and dropouts of each stream from its stamps (eval/stream_timing.h).

#include <optional>
#include <string>
#include <vector>

#include "skerry/eval/allan_deviation.h"
#include "skerry/eval/gnss_error_model.h"
#include "skerry/eval/identified_value.h"
#include "skerry/eval/stream_timing.h"
#include "skerry/io/dataset.h"
#include "skerry/sim/spline_motion.h"
#include "skerry/sim/twin.h"
#include "skerry/twin/drift_detection.h"
#include "skerry/twin/solve_pattern.h"

namespace skerry {

struct TwinIdentifyOptions {
  double min_rest_s = 10.0;  ///< shorter rest periods are not used for the Allan deviation
  /// Which IMU white noise the twin simulates: "rest" (the Allan deviation's, falling back to
  /// the residuals' without a rest period) or "residuals".
  std::string imu_noise = "rest";
  double gross_threshold_sigma = 5.0;
  GnssFitOptions gnss;
};

struct ImuIdentification {
  std::optional<ImuAllanReport> allan;  ///< from the longest rest period, when long enough
  /// Per sensor, the RMS over the axes.
  IdentifiedValue gyro_noise_density;      ///< rad/s/sqrt(Hz), what the twin uses
  IdentifiedValue accel_noise_density;     ///< m/s^2/sqrt(Hz)
  IdentifiedValue gyro_bias_instability;   ///< rad/s (Allan, rest only)
  IdentifiedValue accel_bias_instability;  ///< m/s^2
  IdentifiedValue gyro_random_walk;        ///< rad/s^2/sqrt(Hz) (Allan, rest only)
  IdentifiedValue accel_random_walk;       ///< m/s^3/sqrt(Hz)
  /// From the residuals against the truth (moving and at rest).
  IdentifiedValue residual_gyro_density;
  IdentifiedValue residual_accel_density;
  std::string noise_source;  ///< "rest" or "residuals": where gyro/accel_noise_density come from
  long residual_samples = 0;
};

struct GrossErrorEpisodes {
  int episodes = 0;
  int fixes = 0;  ///< fixes in them
  IdentifiedValue rate_per_hour;
  IdentifiedValue mean_duration_s;      ///< last minus first fix, plus one fix period
  IdentifiedValue offset_horizontal_m;  ///< RMS length of the episodes' mean horizontal offsets
  IdentifiedValue offset_vertical_m;    ///< RMS of their mean vertical offsets
};

struct HeadingIdentification {
  int samples = 0;
  IdentifiedValue sigma_deg;  ///< robust spread of (measured - truth) heading
};

struct TwinIdentification {
  std::optional<StreamTiming> imu_timing, gnss_timing;
  ImuIdentification imu;
  std::optional<GnssErrorModelFit> gnss;  ///< on the fixes outside gross-error episodes
  GrossErrorEpisodes gross;
  GnssResidualSeries gnss_residuals;  ///< every fix in the truth's span
  std::vector<bool> gnss_gross;       ///< per residual: in a gross-error episode
  HeadingIdentification heading;
  /// The batch's gain and the smallest drift seen per probed correlation time (drift_detection.h;
  /// measured by the caller, which runs the batch); empty when not measured.
  std::vector<DriftDetection> drift_detection;
  /// A receiver's solve-and-propagate pattern (solve_pattern.h; looked for by the caller, on a
  /// recording without IMU); empty when not looked for.
  std::optional<SolvePattern> solve_pattern;
  sim::TwinModel model;  ///< what the twin is simulated with
};

/// Identifies the models of `real` against `truth`. Throws InputError naming the dataset when
/// the truth covers fewer than 30 fixes (no GNSS model can be identified) or no IMU sample.
TwinIdentification IdentifyTwin(const Dataset& real,
                                const sim::SplineMotion& truth,
                                const TwinIdentifyOptions& options = {});

/// The residual of every fix of `real` inside `truth`'s span against the truth's antenna
/// (fix - antenna, local east, north, up, m) with the antenna's velocity, t_s from the truth's
/// start: the series IdentifyTwin fits. `fix_index`, when given, gets each residual's index in
/// real.gnss_fixes.
GnssResidualSeries GnssResidualsAgainstTruth(const Dataset& real,
                                             const sim::SplineMotion& truth,
                                             std::vector<size_t>* fix_index = nullptr);

/// gnss_residuals.csv: t (s since the truth's start), e_east, e_north, e_up (m), v_east, v_north,
/// v_up (m/s), gross (0/1).
void WriteGnssResidualsCsv(const std::string& path, const TwinIdentification& id);

/// `real` cut to the truth's span (IMU, GNSS; sensors beyond them dropped): the recording the
/// twin is compared with, over the same time.
Dataset CropToTruth(const Dataset& real, const sim::SplineMotion& truth);

}  // namespace skerry
