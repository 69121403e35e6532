#pragma once
/// \file
/// Configuration of the estimators (window and batch), loaded from YAML with units in key names.
/// Presets live in config/presets/NAME.yaml; see docs/configuration.md.

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "skerry/factors/gnss_drift_factor.h"
#include "skerry/factors/robust_loss.h"

namespace skerry {

/// The Ceres options that matter, as validated strings/numbers.
struct CeresConfig {
  /// or "dogleg": MakeSolverOptions then clamps Ceres' diag(J^T J) scaling to a constant, since
  /// dogleg's fixed 1e-8 damping floor on it stalls the weak GNSS-determined directions.
  std::string trust_region = "levenberg_marquardt";
  std::string dogleg_type = "traditional";               ///< or "subspace"
  std::string linear_solver = "sparse_normal_cholesky";  ///< dense_qr, dense_normal_cholesky,
                                                         ///< dense_schur, sparse_schur,
                                                         ///< iterative_schur, cgnr, or chain
                                                         ///< (NavGraph::SolveChain)
  int max_iterations = 10;
  /// The IMU factors carry far more information than GNSS, so the LM damping 1/radius (on the
  /// Jacobi-scaled normal equations, unit diagonal) throttles the GNSS-determined directions,
  /// whose eigenvalues are ~1e-10 and below, until it is far smaller than they are: Ceres'
  /// default radius (1e4) takes dozens of iterations, 1e10 still 4-10. Start at Ceres' largest
  /// radius (1e16, Gauss-Newton in all but name); a bad step still shrinks it.
  double initial_trust_region_radius = 1e16;
  double max_time_s = 0.2;  ///< per solve; 0 = unlimited
  int num_threads = 1;
  double function_tolerance = 1e-8;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  /// With "chain": the precision of the elimination's stored gains, "double" or "single" (half
  /// the memory of a long batch's solve; block_tridiagonal.h says what it costs in accuracy).
  std::string chain_gains = "double";
};

/// How the first state is found.
struct InitConfig {
  std::string mode = "auto";         ///< "auto": dual-antenna heading if present, else course over
                                     ///< ground; "cog"; "heading"; "given" (caller sets the state);
                                     ///< "align": heading unknown, found by a bank of estimators
                                     ///< started from yaw hypotheses (YawHypothesisBank)
                                     ///< "skyline" / "lidar": the first state from the camera's
                                     ///< or the LiDAR's own global search (sensor_start.h)
  double min_cog_distance_m = 15.0;  ///< displacement between fixes that fixes the COG heading
  double max_cog_time_s = 20.0;      ///< fixes further apart are not paired; with mode auto, no
                                     ///< course over ground this long after the first fix falls
                                     ///< back to align
  double attitude_window_s = 2.0;    ///< accelerometer averaging for roll/pitch
  double roll_pitch_sigma_deg = 3.0;
  double yaw_sigma_deg = 5.0;
  double velocity_sigma_m_s = 1.0;
  double position_sigma_scale = 2.0;  ///< times the fix sigma
  /// "align": seconds the vehicle is at rest at the start of the data (0: a moving start). At
  /// rest, the gyro bias and roll/pitch come from the mean gyro and accelerometer over that time.
  /// kStaticAuto (YAML `auto`, the default): detected from the IMU (rest_detection.h).
  double static_s = kStaticAuto;
  static constexpr double kStaticAuto = -1.0;
  int align_hypotheses = 12;        ///< "align": yaw hypotheses, evenly spaced over 360 deg
  double align_min_s = 20.0;        ///< "align": earliest decision, seconds after the start
  double align_max_s = 120.0;       ///< "align": decide for the likeliest hypothesis by then
  double align_decide_mass = 0.99;  ///< "align": posterior mass the winner's cluster must hold
};

/// The watchdog of NavigationEstimator (navigation_estimator.h): when a window is diverged, and
/// how often it is restarted before giving up.
struct WatchdogConfig {
  bool enabled = true;
  double window_s = 120.0;  ///< the stretch judged after a re-acquisition
  /// After a re-acquisition, at least this many fixes decided, this share or more of them
  /// rejected: the re-acquisition did not hold.
  int min_fixes = 20;
  double rejected_share = 0.5;
  int reacquisitions = 2;  ///< this many re-acquisitions within window_s: diverged
  int max_restarts = 3;    ///< then the estimator stops and says why
};

/// How the estimator treats one sensor beyond IMU and GNSS (YAML `sensors: NAME: ...`, NAME as
/// in dataset.yaml: pose_fixes, camera, lidar_bow, ...).
struct SensorOptions {
  RobustLoss loss{LossType::kHuber, 3.0};
  double gate_probability = 0.999;  ///< chi-square gate on each block; 0 = off
  /// Estimate the sensor's extrinsic T_b_s with a prior at dataset.yaml's value.
  bool calibrate = false;
  double extrinsic_prior_sigma_deg = 1.0;
  double extrinsic_prior_sigma_m = 0.1;
};

/// The skyline frontend (frontends/skyline) of every camera: how its frames become residuals.
struct SkylineConfig {
  int column_stride_px = 8;      ///< one sample every this many image columns
  double sigma_px = 1.0;         ///< noise of one sample
  double correlation_px = 20.0;  ///< correlation length of sample errors along the skyline
  double huber_sigmas = 3.0;     ///< per-sample Huber threshold (0: none)
  /// Correlation time of the skyline's errors from frame to frame, s (0: independent frames).
  /// The DEM's errors and its interpolation stay put while the vessel moves a few metres, so
  /// consecutive frames of one camera repeat much of each other's error: each frame keeps the
  /// share (1 - rho) / (1 + rho) of its information, rho = exp(-dt / this), the information of
  /// an AR(1) sequence per sample.
  double frame_correlation_s = 10.0;
  /// Correlation length of the skyline's errors on the ground, m (0: not modelled; 90: SRTM's
  /// 3" cell). A frame's correlation with the previous one is also measured by how far the
  /// terrain points making its skyline moved, water horizons counting as new
  /// (crest_correlation.h): rho = exp(-dt / frame_correlation_s) times the ground's rho (either
  /// factor 1 when its key is 0).
  double frame_correlation_m = 90.0;
  /// The DEM's height error, m, 1 sigma (0: the map is taken as exact; 4: SRTM's, as
  /// frame_correlation_m's 90 m is its cell). Added to each sample's noise as the horizon it
  /// moves, dem_sigma_m / range, correlated between neighbouring samples over
  /// frame_correlation_m on the ground: a near ridge's skyline counts less than a far range's and
  /// a water horizon's is untouched (SkylineResidualModel::AddMapError).
  double dem_sigma_m = 4.0;
  double min_confidence = 0.5;  ///< samples of the extraction below this confidence are gaps
  int min_samples = 20;         ///< fewer samples: the frame is skipped (counted)
  /// What the camera's images are: "mask" (segmentation, sky = 255), "image" (a photo), or
  /// "auto" (a single-channel image holding only 0 and 255 is a mask).
  std::string source = "auto";
  double refraction_k = 0.13;  ///< coefficient of terrestrial refraction
  /// > 0: the refraction coefficient is estimated with the states, one value per camera for the
  /// run, under a Gaussian prior of this sigma at refraction_k (k over water varies from about
  /// -0.2 to 0.5 with the air's temperature gradient; Hirt et al. 2010). 0: k is taken as known.
  double refraction_k_sigma = 0.0;
  /// The height by which the terrain's crests stand above the DEM's, m: a raster's height is a
  /// mean over its footprint, so the crests that make a skyline lie below the real ones by metres
  /// (docs/skyline.md, "The map's crests"). Land horizons are predicted from crests this much
  /// higher, to first order (SkylineResidualModel); water horizons are untouched.
  double crest_offset_m = 0.0;
  /// > 0: the crest offset is estimated with the states, one value per camera for the run, under
  /// a Gaussian prior of this sigma at crest_offset_m (the DEM's stated accuracy: its bias is
  /// what the prior bounds). The camera's one estimated parameter: not with refraction_k_sigma.
  double crest_offset_sigma_m = 0.0;
  double max_range_m = 60000.0;  ///< terrain further away is not part of the horizon
  double dem_spacing_m = 0.0;    ///< ENU grid spacing of the DEM (0: the DEM's cell / oversampling)
  /// With dem_spacing_m 0, the map's ENU grid at the DEM's own cell divided by this (>= 1), as
  /// far as the grid stays within skyline::kMaxOversampledMapNodes. Resampling a raster onto a
  /// grid of its own cell whose nodes fall between the raster's lowers every crest (a bilinear
  /// surface through points of a bilinear surface never rises above it), and a range's skyline 30
  /// km off sinks by about 0.1 px: taken for tens of metres of range. Half the cell halves the
  /// loss (horizon_for_track.h).
  int dem_oversampling = 2;
  /// > 0: the map is sharpened once made (geo::SharpenTerrain, the first van Cittert iteration
  /// with this gain): a raster's height is a mean over its footprint, so its crests lie below the
  /// terrain's and the skyline it predicts is low; this gives back the relief the footprint took,
  /// to first order. 0: the raster taken as the terrain.
  double dem_sharpening = 0.0;
  /// The footprint's standard deviation in the DEM's cells (its finer axis), for dem_sharpening;
  /// (0, 10].
  double dem_footprint_cells = 0.75;
  /// > 0: the sharpening gain is estimated with the states instead, one value per camera for the
  /// run, under a Gaussian prior of this sigma at dem_sharpening: the map is left as it is and a
  /// land horizon is predicted from crests raised by the gain times what a gain of 1 adds at its
  /// point (to first order, SkylineResidualModel). The camera's one estimated parameter: not with
  /// refraction_k_sigma or crest_offset_sigma_m.
  double dem_sharpening_sigma = 0.0;
  /// After this many frames of a camera in a row rejected by the gate the window re-acquires,
  /// relocated by the global search around its estimate when that finds an unambiguous fix
  /// (0: never).
  int reacquire_after_rejections = 5;
  /// The relocation's search: at least this half-width (m), or 3 sigma of the estimate.
  double relocate_min_radius_m = 300.0;
  /// While the estimate's heading sigma is above this (deg), a frame is first located by the
  /// global search around the estimate (the residual's basin in heading is about half a peak's
  /// width; a start from the course over ground can lie outside it). 0: never.
  double relocate_above_heading_sigma_deg = 0.3;
  /// init.mode skyline: the first frames are searched this far around the dataset origin, m.
  double start_radius_m = 1000.0;
  /// Threads a frame's horizon is traced on (its samples shared among them), the frames read and
  /// extracted on, and the global search's grid searched on; the estimate is the same to the
  /// last bit. Inside the batch's parallel blocks (batch_solver.num_threads) a frame stays on its
  /// block's thread.
  int threads = 1;
};

/// The LiDAR/aerial frontend (frontends/lidar_aerial) of every LiDAR: how its scans become
/// residuals against the dataset's orthophoto (docs/lidar_aerial.md).
struct LidarAerialConfig {
  double resolution_m = 0.25;   ///< the map's grid
  double max_distance_m = 5.0;  ///< distances to the image's edges clipped here
  /// The image's edges (aerial_map.h): blur, then Canny at these quantiles of the gradient. Water
  /// with ripples and textured concrete fill most of a harbour photo, so its edges are the
  /// strongest few per cent of gradients (AerialMapOptions' 0.5 m, 0.90 / 0.75 suit a land scene
  /// such as Autzen's).
  double map_blur_m = 1.0;
  double canny_high_quantile = 0.97;
  double canny_low_quantile = 0.93;
  double sigma_m = 0.5;  ///< one edge point's distance noise
  /// The per-point robust function of the window's blocks and of the batch's: huber, or
  /// geman_mcclure (redescending: a point on a boat that is only in the scan or only in the photo
  /// stops pulling; map_alignment_residual.h). The window keeps Huber's: a redescending loss hides
  /// a misaligned scan's misfit from the gate, which then never rejects the scans that would
  /// trigger a relocation, and its narrower basin holds an estimate that is off for longer (the
  /// 10-minute harbour tour: 1.73 m against 1.42 m). The batch starts
  /// from the window's pass, inside the narrower basin, as graduated non-convexity does (Black
  /// and Rangarajan 1996, sec. 5; Yang et al. 2020, "Graduated non-convexity for robust spatial
  /// perception"), and has no relocation to lose (docs/results.md).
  std::string loss = "huber";
  std::string batch_loss = "geman_mcclure";
  double loss_sigmas = 2.0;  ///< their scale in sigmas (0: plain least squares)
  /// The window's blocks leave out the points farther than this (in sigmas) from an edge where
  /// the scan on its own fits the map best near the prediction (its planar minimum under the
  /// window's loss; planar_minimum.h): what only the scan has (a boat the photo does not show)
  /// pulls no more, while the block keeps Huber's wide basin and the gate sees the misfit of the
  /// prediction. 0: every point. A hard redescending loss decided once, at the scan's own fit, as
  /// ICP's distance threshold on pairings (Zhang 1994, "Iterative point matching for registration
  /// of free-form curves and surfaces", sec. 4); the batch takes batch_loss instead.
  double window_trim_sigmas = 2.0;
  /// A block's information along its weakest horizontal direction is what its cost rises over
  /// +- this (m) from the scan's own minimum, not the local curvature, when that is less
  /// (information_at_scale.h): along a straight breakwater the curvature of texture finer than
  /// the map's edges claims decimetres the cost does not bear out. 0: the local curvature.
  double information_scale_m = 1.0;
  /// A scan weighs at most this many independent points: with sigma_m, its position information.
  /// 25 points of 0.5 m say 0.1 m a scan, as scans of the simulated harbour registered at the
  /// truth scatter (0.25-0.35 m RMS, with the AR(1) share below); 100 made the window 5x
  /// overconfident (position ANEES 21), its gate and relocation blind, and the 10-minute tour
  /// diverge (docs/results.md).
  double effective_points = 25;
  /// Correlation time of the alignment's errors from scan to scan, s (0: independent scans): one
  /// map and its mis-registration under consecutive scans; each scan keeps the share
  /// (1 - rho) / (1 + rho) of its information, rho = exp(-dt / this), as the skyline's frames.
  double scan_correlation_s = 2.0;
  /// Returns lower than this above the body origin, levelled at the estimate, are dropped (the
  /// water and what floats on it: prior work cut at 0.3 m above the water; the body origin is
  /// the waterline).
  double min_height_m = 0.3;
  double max_range_m = 100.0;  ///< horizontal range from the LiDAR
  /// The own hull and superstructure, a box in the body frame whose returns are dropped (min and
  /// max corners, m; equal corners: none).
  std::vector<double> hull_min_b_m = {0.0, 0.0, 0.0};
  std::vector<double> hull_max_b_m = {0.0, 0.0, 0.0};
  double cell_m = 0.5;  ///< the scan's columns
  /// The nearest return per azimuth sector of this many degrees is an edge (a quay's or pier's
  /// edge across the water: scan_preparation.h's fronts); 0: none.
  double front_sector_deg = 0.5;
  /// A wall's returns may be this far apart per metre of range (the beams' fan: 0.035 covers a
  /// 2 degree spacing).
  double wall_gap_per_m = 0.035;
  double max_edge_height_m = 3.0;  ///< edges higher above the local floor are not used (walls are)
  int max_points = 3000;           ///< edge points kept per scan
  int min_points = 30;             ///< fewer: the scan is skipped (counted)
  /// The map covers the orthophoto within this distance of the dataset's track box, m.
  double map_margin_m = 500.0;
  /// One map of that box while it holds at most this many million cells (16: a 1 km square at
  /// 0.25 m, about 110 MB); beyond, tiles of map_tile_m square, each made when the first scan
  /// in it is (aerial_map_tiles.h), so that the map's memory follows the track's length and
  /// not its box. 0: always tiles.
  double map_tile_above_mcells = 16.0;
  double map_tile_m = 250.0;  ///< side of a tile's square (the tile adds the LiDAR's reach)
  /// When the dataset says where the photograph was taken from (maps.orthophoto.viewpoint), the
  /// outlines its perspective displaces are modelled (relief_displacement.h); false: edges are
  /// taken where the image has them.
  bool model_relief = true;
  /// init.mode lidar: the first scans are searched for within this radius of the receiver's fix
  /// (else the origin), m; the coarse search caps it at 50.
  double start_radius_m = 30.0;
  /// While the estimate's horizontal position sigma is above this (m; 0: never), a scan is first
  /// registered on its own around the estimate (coarse search and fine step) and the window
  /// restarts there: the per-point residual's basin is a metre or two among a harbour's edges.
  double relocate_above_position_sigma_m = 1.0;
  /// The same for heading (deg; 0: never), the registration searching all round when 3 sigma is
  /// above 60 degrees. Off by default: on the simulated harbour runs it relocated more often and
  /// did not mend a start at rest with a wrong heading (docs/results.md).
  double relocate_above_heading_sigma_deg = 0.0;
  /// After this many scans in a row rejected by the gate the window re-acquires, relocated by the
  /// scan's registration when it is unambiguous (0: never).
  int reacquire_after_rejections = 3;
};

struct EstimatorConfig {
  std::string name = "default";
  // Keyframes and window.
  double keyframe_rate_hz = 10.0;
  int window_keyframes = 10;             ///< keyframes kept in the window
  double window_s = 0.0;                 ///< if > 0, also marginalise keyframes older than this
  bool first_estimate_jacobians = true;  ///< FEJ in marginalisation
  /// Estimate the gyro's scale factors and misalignment with the states (one 3x3 E for the run,
  /// GyroCalibrationJacobians) under the prior of the dataset's IMU datasheet
  /// (ImuConfig::gyro_scale_factor_sigma_ppm, gyro_misalignment_sigma_mrad); without those in
  /// the dataset, nothing is estimated. On by default: a dataset that states those errors is
  /// estimated with them (docs/results.md, stop 72).
  bool estimate_gyro_calibration = true;
  // Measurements.
  RobustLoss gnss_loss{LossType::kHuber, 3.0};
  RobustLoss heading_loss{LossType::kHuber, 3.0};
  double gnss_gate_probability = 0.999;  ///< chi-square gate on the innovation; 0 = off
  SkylineConfig skyline;
  LidarAerialConfig lidar_aerial;
  double gnss_gate_max_reject_s = 30.0;  ///< after this long of rejections, re-acquire
  /// Rejected fixes further apart than this (an outage between them) start a new streak: time
  /// without fixes is not time of rejections.
  double gnss_gate_streak_max_gap_s = 5.0;
  /// A rejection streak that begins with a step in the innovation (a receiver's jump) refuses
  /// the fixes the jump still explains, and the window re-acquires on the receiver at once when
  /// it steps back from a jump the window followed (gnss_jump_test.h).
  bool gnss_jump_test = true;
  /// A jump outstanding that has explained the streak's fixes for `gnss_jump_step_after_s` (and
  /// at least three of them) is taken into the receiver's drift as a step
  /// (gnss_drift_step_factor.h) and its fixes are taken again: they keep their relative
  /// information instead of being refused for as long as the jump lasts. Needs the drift model
  /// and the jump test.
  bool gnss_jump_as_drift_step = false;
  double gnss_jump_step_after_s = 1.0;
  double gnss_sigma_scale = 1.0;  ///< multiplies the receiver sigmas
  bool use_gnss_heading = true;
  /// First-order Gauss-Markov drift of the GNSS position, estimated as a state (YAML gnss:
  /// drift_sigma_horizontal_m, drift_sigma_vertical_m, drift_tau_s); sigmas 0 switch it off.
  GnssDriftParams gnss_drift;
  // Solver.
  CeresConfig ceres;
  /// "chain": NavGraph::SolveChain, Ceres' LM with the chain's block elimination (0.89x the
  /// CPU time and 0.59x the peak memory of Ceres' sparse normal Cholesky, 60 min of open sea).
  CeresConfig batch_ceres = [] {
    CeresConfig c{
        "levenberg_marquardt", "traditional", "chain", 50, 1e16, 0.0, 1, 1e-10, 1e-12, 1e-10};
    c.chain_gains = "single";  // half the memory of a long batch's solve (block_tridiagonal.h)
    return c;
  }();
  /// Output a covariance with every estimate. The newest keyframe's covariance is computed after
  /// every solve regardless while the gate is on (the gate and re-acquisition need it).
  bool compute_covariance = true;
  InitConfig init;
  WatchdogConfig watchdog;
  /// Per sensor beyond IMU and GNSS; a sensor not listed takes SensorOptions' defaults.
  std::map<std::string, SensorOptions> sensors;

  SensorOptions SensorOptionsFor(const std::string& sensor) const {
    const auto it = sensors.find(sensor);
    return it == sensors.end() ? SensorOptions() : it->second;
  }

  /// The variance of the first position taken from a fix of per-axis sigma `fix_sigma_enu_m`
  /// (the window's start and every hypothesis of the align bank): the fix's sigma times
  /// init.position_sigma_scale and gnss_sigma_scale, plus, with the receiver's drift modelled,
  /// its stationary variance, since at the start the drift may be anywhere in its stationary
  /// distribution (gnss_drift_factor.h) and the fix is the position plus the drift.
  Eigen::Vector3d StartPositionVariance(const Eigen::Vector3d& fix_sigma_enu_m) const {
    Eigen::Vector3d var =
        (fix_sigma_enu_m * init.position_sigma_scale * gnss_sigma_scale).array().square();
    if (gnss_drift.enabled()) var += gnss_drift.StationarySigma().array().square().matrix();
    return var;
  }
};

/// Loads a YAML file; keys not given keep their defaults, unknown keys are errors.
/// Throws InputError(file, line, key path, ...).
///
/// `overrides` are the command line's `--set KEY=VALUE`, applied to the file's YAML before it is
/// read, in order: KEY a dotted path (`skyline.dem_spacing_m`; missing sections are made),
/// VALUE YAML (`63`, `huber`, `[1, 2]`). The file's other keys keep theirs, so one key can be
/// changed on a preset. Each is checked as the file's keys are; an error in one names it as
/// InputError(kCommandLine, 0, "--set KEY", ...).
EstimatorConfig LoadEstimatorConfig(const std::string& path,
                                    const std::vector<std::string>& overrides = {});

/// Checks a configuration a program built as LoadEstimatorConfig checks a file's (every range,
/// name and combination); std::invalid_argument naming the key path (e.g. `skyline.sigma_px`)
/// and what is wrong. The estimators and the batch call it on the configuration they are given.
void ValidateEstimatorConfig(const EstimatorConfig& config);

/// Tag for an estimator's constructor: its configuration has passed ValidateEstimatorConfig
/// already. For an owner that builds estimators from one configuration again and again (a
/// restart, the hypotheses of an alignment) and checks it once, where it is given.
struct ConfigValidated {
  explicit ConfigValidated() = default;
};

/// A preset NAME from $SKERRY_PRESET_DIR, the install share dir, or the source tree's
/// config/presets; or, if `name_or_path` is a file, that file.
/// `overrides` as LoadEstimatorConfig's.
EstimatorConfig LoadPreset(const std::string& name_or_path,
                           const std::vector<std::string>& overrides = {});

/// The YAML text of a configuration (for summary.json and reproducibility).
std::string ToYaml(const EstimatorConfig& config);

}  // namespace skerry
