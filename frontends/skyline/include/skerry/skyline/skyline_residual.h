#pragma once
/// \file
/// The residual of one camera frame's skyline against the terrain horizon re-predicted at the
/// current estimate: per observed skyline sample (pixel u, v), the elevation of its ray minus the
/// horizon's elevation at the ray's azimuth, seen from the camera's current position, in pixels.
///
/// For sample i with unit ray r_c (optical frame) and the pose T_w_b, extrinsic T_b_c:
///   r_w = R_w_b R_b_c r_c,  a = atan2(r_w.x, r_w.y),  e_obs = atan2(r_w.z, |r_w.xy|)
///   p_c = p_w_b + R_w_b p_b_c,  e_i = s_i (e_obs - E(p_c, a)) / sigma_i
/// with E the horizon (horizon_predictor.h) and s_i the pixels per radian of elevation at the
/// sample (how far the pixel moves as its ray is raised, distortion included). E is traced again at
/// every evaluation, so the terrain point making the skyline slides as the camera moves; its
/// derivatives are the envelope theorem's. Samples whose horizon is truncated (the map ends there)
/// or missing at the current estimate give 0 with zero Jacobian.
///
/// The map's crests: a raster's height is a mean over its footprint, so the crests making a land
/// skyline stand above the DEM's by some metres (docs/skyline.md). The land horizon is predicted
/// from its point raised by a crest offset c (m) and a sharpening gain g times the map's detail D
/// there (what a sharpening of gain 1 adds, HorizonPredictor::DetailAt), to first order in the
/// raise over the distance:
///   E' = E + (c + g D) cos^2(E) / d
/// (E = atan(dz / d) with d the horizontal distance to the horizon's point, so dE / dz =
/// cos^2(E) / d, as in AddMapError; the envelope theorem again keeps the point). A water horizon
/// (HorizonOnWater) has no crest and is left as it is.
///
/// Robustness and weighting: each e_i goes through a per-sample Huber in square-root form
/// (r -> sign(r) sqrt(2 c |r| - c^2) beyond c: its square is Huber's rho; Triggs et al. 1999,
/// "Bundle adjustment: a modern synthesis", sec. 3.3) so that one mis-extracted column (a boat, a
/// cloud edge) cannot pull the pose; then the errors of neighbouring columns, correlated because
/// they see the same DEM cells and the same extraction blur, are whitened as a first-order
/// Gauss-Markov sequence along the skyline, rho = exp(-du / l):
///   w_0 = e_0,  w_i = (e_i - rho_i e_{i-1}) / sqrt(1 - rho_i^2)
/// (the exact whitening of an AR(1) process), restarting after gaps, so that 240 samples of a
/// frame carry the information of about (width / l) independent ones, not 240.

#include <ceres/cost_function.h>
#include <ceres/jet.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <mutex>
#include <vector>

#include "skerry/skyline/camera_model.h"
#include "skerry/skyline/horizon_predictor.h"

namespace skerry::skyline {

struct SkylineResidualOptions {
  /// Noise of one skyline sample, px (extraction, pixel quantisation, and the DEM's own error
  /// unless AddMapError gives each sample its share of that).
  double sigma_px = 1.0;
  /// Correlation length of the sample errors along the skyline, px.
  double correlation_px = 20.0;
  /// Per-sample Huber threshold in sigmas (<= 0: none).
  double huber_sigmas = 3.0;
  /// Samples further apart than this (px) start a new correlated chain.
  double max_chain_gap_px = 40.0;
  /// Every residual is multiplied by this: the share of a frame's information that is its own
  /// when its errors are correlated with the previous frames' (skyline_frontend.h).
  double frame_weight = 1.0;
  /// The crest offset c (m) and sharpening gain g (above) that Evaluate without explicit ones and
  /// PixelErrors use.
  double crest_offset_m = 0.0;
  double detail_gain = 0.0;
  /// Threads the samples' horizon is traced on (core/parallel_for.h; one inside another
  /// ParallelFor). The residuals do not depend on it.
  int threads = 1;
};

/// One observed skyline sample.
struct SkylineSample {
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  /// Relative weight from the extraction's confidence (sigma_i = sigma_px / sqrt(weight)).
  double weight = 1.0;
};

/// The numbers of the map a frame is evaluated with (above): estimated ones, or the options'.
struct SkylineMapParameters {
  double refraction_k = 0.13;   ///< coefficient of terrestrial refraction
  double crest_offset_m = 0.0;  ///< c, m
  double detail_gain = 0.0;     ///< g
};

/// Where Evaluate writes the residuals' derivatives by those numbers (n each; null: not wanted).
struct SkylineMapJacobians {
  Eigen::VectorXd* refraction_k = nullptr;
  Eigen::VectorXd* crest_offset_m = nullptr;
  Eigen::VectorXd* detail_gain = nullptr;
};

/// The residual model of one frame (no Ceres): what the cost function and the single-frame
/// search evaluate.
class SkylineResidualModel {
 public:
  /// Samples whose pixel cannot be undistorted are dropped. std::invalid_argument when none is
  /// left.
  SkylineResidualModel(std::shared_ptr<const HorizonPredictor> horizon,
                       const CameraModel& camera,
                       const std::vector<SkylineSample>& samples,
                       const SkylineResidualOptions& options);

  int size() const { return static_cast<int>(rays_c_.size()); }

  /// Sets SkylineResidualOptions::frame_weight (> 0) after construction. Not safe while the model
  /// is evaluated elsewhere: call before it is shared.
  void SetFrameWeight(double frame_weight);

  /// Adds the map's own height error to each sample's noise, as seen from the camera pose
  /// (r_w_c, p_w_c): a DEM wrong by `dem_sigma_m` (1 sigma, >= 0) at the terrain point that makes
  /// a sample's horizon, a horizontal distance d away at apparent elevation E, moves that horizon
  /// by dem_sigma_m cos^2(E) / d rad (E = atan(dz / d): dE / dz = cos^2(E) / d): the map's part of
  /// the sample's error, m_i = s_i dem_sigma_m cos^2(E) / d px, beside the extraction's
  /// sigma_px / sqrt(weight). A near ridge's skyline carries the map's error magnified, a far
  /// range's little of it; a horizon made by water (HorizonOnWater) none, nor one that is
  /// truncated or missing there. The map's error is a field on the ground with correlation
  /// exp(-distance / correlation_m) (0: none), so neighbouring samples whose horizon points are
  /// close share it; the two errors together are whitened along the skyline as a first-order
  /// Gauss-Markov sequence with each pair's lag-1 correlation
  ///   rho_i = (sx_i sx_{i-1} rho_px + m_i m_{i-1} rho_map) / (sigma_i sigma_{i-1})
  /// (sigma_i^2 = sx_i^2 + m_i^2), the exact correlation of the sum of the two independent
  /// errors at lag 1. Replaces the map term of an earlier call; 0 gives back the model without
  /// it. Not safe while the model is evaluated elsewhere. Returns the mean of m_i over the
  /// samples it weighted, px (0 when none).
  double AddMapError(const Eigen::Matrix3d& r_w_c,
                     const Eigen::Vector3d& p_w_c,
                     double dem_sigma_m,
                     double correlation_m = 0.0);

  /// Whitened residuals at a camera pose (R_w_c, p_w_c); `jac_rot` (n x 3: d r / d theta for a
  /// perturbation R_w_c <- Exp(theta) R_w_c, world frame) and `jac_pos` (n x 3) when not null.
  /// Returns the number of active samples.
  ///
  /// The horizon traced at the last pose evaluated is kept (one pose, per model): a solver
  /// evaluates a candidate step's cost and then, once the step is taken, linearises at the same
  /// pose, and a gate linearises at the prediction where the window's first solve starts; those
  /// second evaluations re-use the traces instead of marching the DEM again (bit-identical
  /// results; ~80 bytes per sample held). Safe to call from several threads.
  int Evaluate(const Eigen::Matrix3d& r_w_c,
               const Eigen::Vector3d& p_w_c,
               double* residuals,
               Eigen::Matrix<double, Eigen::Dynamic, 3>* jac_rot = nullptr,
               Eigen::Matrix<double, Eigen::Dynamic, 3>* jac_pos = nullptr) const {
    return Evaluate(r_w_c, p_w_c, MapParameters(), residuals, jac_rot, jac_pos);
  }
  /// The same with the map's numbers `map` (estimated ones) and their derivatives into `jac_map`.
  /// The cache holds one (pose, k); c and g need no new trace.
  int Evaluate(const Eigen::Matrix3d& r_w_c,
               const Eigen::Vector3d& p_w_c,
               const SkylineMapParameters& map,
               double* residuals,
               Eigen::Matrix<double, Eigen::Dynamic, 3>* jac_rot,
               Eigen::Matrix<double, Eigen::Dynamic, 3>* jac_pos,
               const SkylineMapJacobians& jac_map = {}) const;
  /// The map's numbers of the options and the horizon (refraction_k, crest_offset_m,
  /// detail_gain).
  SkylineMapParameters MapParameters() const {
    return {horizon_->options().refraction_k, options_.crest_offset_m, options_.detail_gain};
  }

  /// The terrain point making each sample's horizon from the camera pose (r_w_c, p_w_c), NaN
  /// where the sample has none there (missing, truncated, or its ray straight up or down). Traced
  /// into the cache Evaluate reads, so what a consumer measures at the pose its block starts from
  /// (the crest's motion, AddMapError) and the first evaluation there share one trace.
  std::vector<Eigen::Vector3d> HorizonPoints(const Eigen::Matrix3d& r_w_c,
                                             const Eigen::Vector3d& p_w_c) const;

  /// Unwhitened per-sample errors in px (NaN where inactive): for reports and the gate's tests.
  std::vector<double> PixelErrors(const Eigen::Matrix3d& r_w_c, const Eigen::Vector3d& p_w_c) const;

  const std::vector<Eigen::Vector3d>& rays_c() const { return rays_c_; }
  const HorizonPredictor& horizon() const { return *horizon_; }
  const SkylineResidualOptions& options() const { return options_; }
  /// Poses at which Evaluate traced the horizon (the evaluations the cache did not serve).
  long traced_poses() const;

 private:
  std::shared_ptr<const HorizonPredictor> horizon_;
  SkylineResidualOptions options_;
  std::vector<Eigen::Vector3d> rays_c_;
  std::vector<double> px_per_rad_;    ///< s_i: px per rad of elevation at the sample
  std::vector<double> weight_;        ///< the sample's relative weight (SkylineSample::weight)
  std::vector<double> map_sigma_px_;  ///< the map's term of sigma_i (AddMapError), px
  std::vector<bool> chained_;         ///< the sample continues the previous one's chain
  std::vector<double> rho_px_;        ///< the extraction's correlation with the previous sample
  std::vector<double> rho_map_;       ///< the map's correlation with the previous sample
  std::vector<double> scale_;         ///< s_i * frame_weight / sigma_i
  std::vector<double> rho_;           ///< correlation with the previous sample (0: chain start)
  void UpdateScales();

  /// What Evaluate needs of one sample's horizon trace.
  struct TracedSample {
    double elevation_rad = 0.0;
    double d_elevation_d_azimuth = 0.0;
    Eigen::Vector3d d_elevation_d_p = Eigen::Vector3d::Zero();
    Eigen::Vector3d point_w = Eigen::Vector3d::Zero();  ///< the terrain point making it
    double distance_m = 0.0;                            ///< horizontal distance to that point
    double d_elevation_d_refraction = 0.0;
    /// dE / dc of the crest offset: cos^2(E) / d on land, 0 on water.
    double d_elevation_d_crest = 0.0;
    double detail_m = 0.0;  ///< the map's detail D at the point (0 on water)
    bool usable = false;    ///< valid and not truncated
  };
  /// The traces at the pose last evaluated (see Evaluate); empty before the first.
  struct TraceCache {
    std::mutex mutex;
    Eigen::Matrix3d r_w_c;
    Eigen::Vector3d p_w_c;
    double refraction_k = 0.0;
    std::vector<TracedSample> samples;
    long traced_poses = 0;
  };
  /// The samples' horizon at (r_w_c, p_w_c) with refraction k, from the cache when it holds
  /// that exact pose and k.
  void TraceAll(const Eigen::Matrix3d& r_w_c,
                const Eigen::Vector3d& p_w_c,
                double refraction_k,
                std::vector<TracedSample>* out) const;
  void TraceAll(const Eigen::Matrix3d& r_w_c,
                const Eigen::Vector3d& p_w_c,
                std::vector<TracedSample>* out) const {
    TraceAll(r_w_c, p_w_c, horizon_->options().refraction_k, out);
  }
  std::unique_ptr<TraceCache> cache_ = std::make_unique<TraceCache>();
};

/// Which number of the map the camera estimates with the states, as its sensor parameter
/// (solvers/sensor_block.h: one per camera for the run).
enum class SkylineParameter {
  kNone,
  kRefraction,   ///< the coefficient of terrestrial refraction k
  kCrestOffset,  ///< the crest offset c, m
  kDetailGain,   ///< the sharpening gain g (the horizon's map must carry its detail)
};

/// The Ceres cost of one frame: parameter blocks q_w_b (4, Eigen order), p_w_b (3), q_b_c (4),
/// p_b_c (3), and unless `parameter` is kNone the estimated one (1: the camera's sensor
/// parameter, solvers/sensor_block.h); residuals: one per sample. What is not estimated is the
/// model's (SkylineResidualModel::MapParameters).
class SkylineCost : public ceres::CostFunction {
 public:
  explicit SkylineCost(std::shared_ptr<const SkylineResidualModel> model,
                       SkylineParameter parameter = SkylineParameter::kNone);
  bool Evaluate(double const* const* parameters,
                double* residuals,
                double** jacobians) const override;
  const SkylineResidualModel& model() const { return *model_; }

  /// The camera pose (R_w_c, p_w_c) of the parameter blocks, computed as Evaluate computes it: a
  /// pose given to the model this way is bit-identical to the one the solver's first evaluation
  /// at the same blocks gives it, so that evaluation re-uses the traces made for it.
  static void CameraPose(const Eigen::Quaterniond& q_w_b,
                         const Eigen::Vector3d& p_w_b,
                         const Eigen::Quaterniond& q_b_c,
                         const Eigen::Vector3d& p_b_c,
                         Eigen::Matrix3d* r_w_c,
                         Eigen::Vector3d* p_w_c);

 private:
  std::shared_ptr<const SkylineResidualModel> model_;
  SkylineParameter parameter_ = SkylineParameter::kNone;
};

}  // namespace skerry::skyline
