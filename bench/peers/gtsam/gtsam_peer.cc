// gtsam_peer: runs a skerry dataset folder (docs/dataset-format.md) through GTSAM with skerry's
// sensor model, for the peer benchmark only (bench/peers/gtsam/README.md). Never part of
// skerry's build: it links GTSAM, which skerry does not depend on.
//
//   gtsam_peer --dataset DIR --mode isam2|batch-fixed-lag|batch-lm --out OUT.tum [--json J]
//              [--update-every-fix (default) | --update-every-keyframe] [--lag S]
//              [--isam2-factorization cholesky|qr] [--integration-cov M2_PER_S]
//
// The graph per keyframe k: pose X(k) (body in local ENU), velocity V(k), IMU bias B(k) and
// GNSS drift G(k); CombinedImuFactor between consecutive keyframes (Forster et al., T-RO 2017,
// with the bias random walk inside the factor), a first-order Gauss-Markov drift factor between
// consecutive G, and a lever-arm GNSS factor per accepted fix. What it writes: the body pose of
// every keyframe as it was when that keyframe was newest (batch-lm: the final solution), and one
// JSON line of timing figures on stdout (and in --json): the total, and apart from it the
// smoother's updates and the gate's covariance queries.
#include <gtsam/inference/Symbol.h>
#include <gtsam/linear/GaussianFactorGraph.h>
#include <gtsam/navigation/CombinedImuFactor.h>
#include <gtsam/navigation/NavState.h>
#include <gtsam/nonlinear/BatchFixedLagSmoother.h>
#include <gtsam/nonlinear/ISAM2.h>
#include <gtsam/nonlinear/LevenbergMarquardtOptimizer.h>
#include <gtsam/nonlinear/Marginals.h>
#include <gtsam/nonlinear/NonlinearFactor.h>
#include <gtsam/nonlinear/NonlinearFactorGraph.h>
#include <gtsam/nonlinear/PriorFactor.h>
#include <gtsam/nonlinear/Values.h>
#include <gtsam_unstable/nonlinear/IncrementalFixedLagSmoother.h>
#include <sys/resource.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <GeographicLib/Constants.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <GeographicLib/NormalGravity.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using gtsam::Key;
using gtsam::Matrix;
using gtsam::Pose3;
using gtsam::Rot3;
using gtsam::Vector3;
using gtsam::symbol_shorthand::B;  // IMU bias (gyro, accel: GTSAM's order is accel, gyro)
using gtsam::symbol_shorthand::G;  // GNSS drift, metres, ENU
using gtsam::symbol_shorthand::V;  // velocity in the world frame
using gtsam::symbol_shorthand::X;  // body pose T_w_b

constexpr double kDeg = M_PI / 180.0;

// ---------------------------------------------------------------------------------------------
// Options: the defaults are skerry's config/presets/default.yaml and docs/configuration.md.

struct Options {
  std::string dataset;
  std::string mode = "isam2";
  std::string out_tum;
  std::string json;
  double keyframe_rate_hz = 10.0;  // keyframe_rate_hz
  double lag_s = 3.0;              // the smoothers' lag (the brief of this benchmark)
  bool isam2_qr = false;           // iSAM2's factorization: GTSAM's default Cholesky, or QR
  // When the smoother is updated: only when a GNSS fix arrives (and at the latest once per lag,
  // during outages), all keyframes since the last update in one update, as skerry solves; or at
  // every keyframe (--update-every-keyframe). Same accuracy, a third of the time (README).
  bool update_every_fix = true;
  // GTSAM's integrationCovariance (m^2/s, position random walk of the preintegration). skerry has
  // none; 1e-12 matches that and makes iSAM2's Cholesky fail on a MEMS IMU after a long outage
  // (README, "iSAM2 and Cholesky"); 1e-6 (1 mm/sqrt(s)) keeps the normal equations factorable.
  double integration_cov = 1e-6;
  double huber_k = 3.0;  // gnss.loss_scale, in sigmas
  double gate_probability = 0.999;
  double gate_max_reject_s = 30.0;     // gnss.gate_max_reject_s
  double gate_streak_max_gap_s = 5.0;  // gnss.gate_streak_max_gap_s
  double drift_sigma_h = 0.15;         // gnss.drift_sigma_horizontal_m
  double drift_sigma_v = 0.3;          // gnss.drift_sigma_vertical_m
  double drift_tau_s = 300.0;          // gnss.drift_tau_s
  int window_max_iterations = 10;      // solver.max_iterations (batch-fixed-lag's LM)
  double window_tolerance = 1e-6;      // solver.function_tolerance
  int batch_max_iterations = 50;       // batch_solver.max_iterations (batch-lm)
  // init: (course over ground start, docs/estimator.md "Start-up")
  double min_cog_distance_m = 15.0;
  double max_cog_time_s = 20.0;
  double attitude_window_s = 2.0;
  double roll_pitch_sigma_deg = 3.0;
  double yaw_sigma_deg = 5.0;
  double velocity_sigma_m_s = 1.0;
  double position_sigma_scale = 2.0;
};

void Usage() {
  std::cerr << "usage: gtsam_peer --dataset DIR --mode isam2|batch-fixed-lag|batch-lm --out "
               "OUT.tum [--json FILE] [--lag S] [--keyframe-rate HZ] [--isam2-factorization "
               "cholesky|qr] [--update-every-fix | --update-every-keyframe] [--integration-cov "
               "M2_PER_S]\n";
}

Options ParseArgs(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(a + ": missing value");
      return argv[++i];
    };
    if (a == "--dataset") {
      o.dataset = next();
    } else if (a == "--mode") {
      o.mode = next();
    } else if (a == "--out") {
      o.out_tum = next();
    } else if (a == "--json") {
      o.json = next();
    } else if (a == "--lag") {
      o.lag_s = std::stod(next());
    } else if (a == "--isam2-factorization") {
      const std::string f = next();
      if (f != "qr" && f != "cholesky") throw std::runtime_error(a + ": qr or cholesky");
      o.isam2_qr = f == "qr";
    } else if (a == "--keyframe-rate") {
      o.keyframe_rate_hz = std::stod(next());
    } else if (a == "--update-every-fix") {
      o.update_every_fix = true;
    } else if (a == "--update-every-keyframe") {
      o.update_every_fix = false;
    } else if (a == "--integration-cov") {
      o.integration_cov = std::stod(next());
      if (!(o.integration_cov > 0)) throw std::runtime_error(a + ": a positive m^2/s");
    } else if (a == "-h" || a == "--help") {
      Usage();
      std::exit(0);
    } else {
      throw std::runtime_error("unknown argument " + a);
    }
  }
  if (o.dataset.empty() || o.out_tum.empty()) throw std::runtime_error("--dataset and --out");
  if (o.mode != "isam2" && o.mode != "batch-fixed-lag" && o.mode != "batch-lm") {
    throw std::runtime_error("--mode: isam2, batch-fixed-lag or batch-lm");
  }
  return o;
}

// ---------------------------------------------------------------------------------------------
// The dataset (docs/dataset-format.md). Times are parsed as doubles: the simulator's clock starts
// at 0, where a double keeps nanoseconds.

struct ImuSample {
  double t;
  Vector3 w;  // rad/s, IMU frame
  Vector3 a;  // specific force, m/s^2, IMU frame
};

struct Fix {
  double t;
  Vector3 z;              // antenna position in local ENU (w)
  Vector3 sigma;          // receiver's 1-sigma along the local level at the fix
  Eigen::Matrix3d R_w_n;  // local level at the fix -> w
  double heading_rad;     // dual-antenna heading of the baseline, clockwise from north; NaN: none
  double sigma_heading_rad;
};

struct Dataset {
  double lat0, lon0, h0;
  bool wgs84 = true;
  double flat_gravity = 9.80665;
  Pose3 T_b_i;
  double gyro_nd, accel_nd, gyro_rw, accel_rw;
  double gyro_prior = 1e-3, accel_prior = 0.05;  // dataset-format.md defaults
  Vector3 lever_arm;
  Vector3 baseline = Vector3(1, 0, 0);  // dual-antenna baseline direction in the body
  std::vector<ImuSample> imu;
  std::vector<Fix> fixes;
};

std::vector<std::vector<double>> ReadCsv(const std::string& path, size_t min_cols) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string line;
  std::getline(in, line);  // header
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    if (line.empty() || line == "\r") continue;
    std::vector<double> row;
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) {
      const bool blank = field.find_first_not_of(" \r") == std::string::npos;
      row.push_back(blank ? NAN : std::stod(field));
    }
    if (row.size() < min_cols) throw std::runtime_error(path + ": short row: " + line);
    rows.push_back(std::move(row));
  }
  return rows;
}

Vector3 Vec3(const YAML::Node& n) {
  return Vector3(n[0].as<double>(), n[1].as<double>(), n[2].as<double>());
}

Dataset LoadDataset(const std::string& dir) {
  Dataset d;
  const YAML::Node y = YAML::LoadFile(dir + "/dataset.yaml");
  d.lat0 = y["origin"]["lat_deg"].as<double>();
  d.lon0 = y["origin"]["lon_deg"].as<double>();
  d.h0 = y["origin"]["height_m"].as<double>();
  if (y["earth"] && y["earth"]["model"].as<std::string>() == "flat") {
    d.wgs84 = false;
    if (y["earth"]["gravity_m_s2"]) d.flat_gravity = y["earth"]["gravity_m_s2"].as<double>();
  }
  const YAML::Node imu = y["sensors"]["imu"];
  const YAML::Node q = imu["T_b_i"]["q_xyzw"];
  const Eigen::Quaterniond q_b_i(q[3].as<double>(), q[0].as<double>(), q[1].as<double>(),
                                 q[2].as<double>());
  d.T_b_i = Pose3(Rot3(q_b_i.normalized()), Vec3(imu["T_b_i"]["p_m"]));
  d.gyro_nd = imu["gyro_noise_density_rad_s_sqrt_hz"].as<double>();
  d.accel_nd = imu["accel_noise_density_m_s2_sqrt_hz"].as<double>();
  d.gyro_rw = imu["gyro_bias_random_walk_rad_s2_sqrt_hz"].as<double>();
  d.accel_rw = imu["accel_bias_random_walk_m_s3_sqrt_hz"].as<double>();
  if (imu["gyro_bias_prior_sigma_rad_s"]) {
    d.gyro_prior = imu["gyro_bias_prior_sigma_rad_s"].as<double>();
  }
  if (imu["accel_bias_prior_sigma_m_s2"]) {
    d.accel_prior = imu["accel_bias_prior_sigma_m_s2"].as<double>();
  }
  const YAML::Node gnss = y["sensors"]["gnss"];
  if (!gnss) throw std::runtime_error(dir + "/dataset.yaml: sensors.gnss: the client needs GNSS");
  d.lever_arm = Vec3(gnss["lever_arm_b_m"]);
  if (gnss["baseline_b"]) d.baseline = Vec3(gnss["baseline_b"]).normalized();

  const std::string imu_file = imu["file"] ? imu["file"].as<std::string>() : "imu.csv";
  for (const auto& r : ReadCsv(dir + "/" + imu_file, 7)) {
    d.imu.push_back({r[0], Vector3(r[1], r[2], r[3]), Vector3(r[4], r[5], r[6])});
  }
  // Fixes: lat/lon/h -> w with GeographicLib's LocalCartesian at the origin (the frame skerry
  // works in), and the rotation of the fix's local level into w, in which the receiver's sigmas
  // are given (docs/estimator.md, "GNSS position": 3 mrad at 20 km).
  const GeographicLib::LocalCartesian enu(d.lat0, d.lon0, d.h0);
  const std::string gnss_file = gnss["file"] ? gnss["file"].as<std::string>() : "gnss.csv";
  for (const auto& r : ReadCsv(dir + "/" + gnss_file, 7)) {
    Fix f;
    f.t = r[0];
    std::vector<double> M(9);
    double x, yy, z;
    enu.Forward(r[1], r[2], r[3], x, yy, z, M);
    f.z = Vector3(x, yy, z);
    // M takes the local ENU at the point to the ENU at the origin, row-major.
    f.R_w_n << M[0], M[1], M[2], M[3], M[4], M[5], M[6], M[7], M[8];
    f.sigma = Vector3(r[4], r[5], r[6]);
    f.heading_rad = r.size() >= 9 ? r[7] * kDeg : NAN;
    // skerry takes heading sigmas below 0.001 deg as 0.001 deg (docs/estimator.md).
    f.sigma_heading_rad = r.size() >= 9 ? std::max(r[8], 1e-3) * kDeg : NAN;
    d.fixes.push_back(f);
  }
  if (d.imu.size() < 2 || d.fixes.empty()) throw std::runtime_error("no IMU or no fixes");
  return d;
}

// ---------------------------------------------------------------------------------------------
// The Earth at the origin (docs/estimator.md, "The Earth"): WGS84 normal gravity (Moritz 1980,
// GRS80, via GeographicLib NormalGravity, centrifugal term included) and the Earth's rate in the
// local ENU frame, (0, cos lat, sin lat) * omega. GTSAM takes one constant gravity vector and a
// first-order Coriolis correction; skerry evaluates gravity along the track (see README).

struct Earth {
  Vector3 gravity_w;
  Vector3 omega_ie_w;
};

Earth EarthAtOrigin(const Dataset& d) {
  Earth e;
  if (!d.wgs84) {
    e.gravity_w = Vector3(0, 0, -d.flat_gravity);
    e.omega_ie_w.setZero();
    return e;
  }
  const GeographicLib::NormalGravity& ng = GeographicLib::NormalGravity::WGS84();
  double gy = 0, gz = 0;
  ng.Gravity(d.lat0, d.h0, gy, gz);  // northward and upward components, m/s^2
  e.gravity_w = Vector3(0.0, gy, gz);
  const double omega = ng.AngularVelocity();
  e.omega_ie_w = omega * Vector3(0.0, std::cos(d.lat0 * kDeg), std::sin(d.lat0 * kDeg));
  return e;
}

// ---------------------------------------------------------------------------------------------
// Factors written for this client.

// A GNSS antenna position: z = p + v dt + R l + gb (skerry's GnssPositionFactor,
// docs/estimator.md "GNSS position"): the keyframe moved to the fix time by its velocity, the
// lever arm l turned into w by the pose, the Gauss-Markov drift gb. Whitened by
// diag(1/sigma) R_n_w, so the receiver's sigmas act along the local level at the fix.
class LeverArmGnssFactor : public gtsam::NoiseModelFactorN<Pose3, gtsam::Vector3, gtsam::Vector3> {
 public:
  using Base = gtsam::NoiseModelFactorN<Pose3, gtsam::Vector3, gtsam::Vector3>;
  LeverArmGnssFactor(Key x,
                     Key v,
                     Key g,
                     const Vector3& z,
                     const Vector3& lever_arm,
                     double dt,
                     const gtsam::SharedNoiseModel& model)
      : Base(model, x, v, g), z_(z), lever_arm_(lever_arm), dt_(dt) {}

  gtsam::Vector evaluateError(const Pose3& pose,
                              const gtsam::Vector3& vel,
                              const gtsam::Vector3& gb,
                              gtsam::OptionalMatrixType H_pose,
                              gtsam::OptionalMatrixType H_vel,
                              gtsam::OptionalMatrixType H_gb) const override {
    gtsam::Matrix36 H;
    const gtsam::Point3 antenna = pose.transformFrom(lever_arm_, H_pose ? &H : nullptr);
    if (H_pose) *H_pose = H;
    if (H_vel) *H_vel = dt_ * gtsam::I_3x3;
    if (H_gb) *H_gb = gtsam::I_3x3;
    return antenna + dt_ * vel + gb - z_;
  }

  gtsam::NonlinearFactor::shared_ptr clone() const override {
    return std::make_shared<LeverArmGnssFactor>(*this);
  }

 private:
  Vector3 z_;
  Vector3 lever_arm_;
  double dt_;
};

// A dual-antenna heading (skerry's GnssHeadingFactor, docs/estimator.md): with u_n = R_n_w R b
// the baseline in the local level at the fix, r = wrap(atan2(u_e, u_n) - z), clockwise from the
// local north. Jacobian for GTSAM's body-frame rotation perturbation, R Exp(d) b ~ R b - R [b]x d.
class GnssHeadingFactor : public gtsam::NoiseModelFactorN<Pose3> {
 public:
  using Base = gtsam::NoiseModelFactorN<Pose3>;
  GnssHeadingFactor(Key x,
                    double z,
                    const Vector3& baseline,
                    const Eigen::Matrix3d& R_n_w,
                    const gtsam::SharedNoiseModel& model)
      : Base(model, x), z_(z), baseline_(baseline), R_n_w_(R_n_w) {}

  gtsam::Vector evaluateError(const Pose3& pose, gtsam::OptionalMatrixType H) const override {
    const Eigen::Matrix3d R = pose.rotation().matrix();
    const Vector3 u = R_n_w_ * R * baseline_;
    const double psi = std::atan2(u.x(), u.y());
    if (H) {
      const double n2 = u.x() * u.x() + u.y() * u.y();
      const Eigen::RowVector3d dpsi_du(u.y() / n2, -u.x() / n2, 0.0);
      *H = gtsam::Matrix::Zero(1, 6);
      H->leftCols<3>() = -dpsi_du * R_n_w_ * R * gtsam::skewSymmetric(baseline_);
    }
    return gtsam::Vector1(std::remainder(psi - z_, 2.0 * M_PI));
  }

  gtsam::NonlinearFactor::shared_ptr clone() const override {
    return std::make_shared<GnssHeadingFactor>(*this);
  }

 private:
  double z_;
  Vector3 baseline_;
  Eigen::Matrix3d R_n_w_;
};

// First-order Gauss-Markov drift between consecutive keyframes, exactly discretised: gb_j =
// phi gb_i + w, phi = exp(-dt/tau), Var(w) = sigma^2 (1 - phi^2) per axis (Maybeck 1979, vol. 1
// sec. 4.9; skerry's GnssDriftFactor).
class GaussMarkovDriftFactor : public gtsam::NoiseModelFactorN<gtsam::Vector3, gtsam::Vector3> {
 public:
  using Base = gtsam::NoiseModelFactorN<gtsam::Vector3, gtsam::Vector3>;
  GaussMarkovDriftFactor(Key gi, Key gj, double phi, const gtsam::SharedNoiseModel& model)
      : Base(model, gi, gj), phi_(phi) {}

  gtsam::Vector evaluateError(const gtsam::Vector3& gi,
                              const gtsam::Vector3& gj,
                              gtsam::OptionalMatrixType H_i,
                              gtsam::OptionalMatrixType H_j) const override {
    if (H_i) *H_i = -phi_ * gtsam::I_3x3;
    if (H_j) *H_j = gtsam::I_3x3;
    return gj - phi_ * gi;
  }

  gtsam::NonlinearFactor::shared_ptr clone() const override {
    return std::make_shared<GaussMarkovDriftFactor>(*this);
  }

 private:
  double phi_;
};

// ---------------------------------------------------------------------------------------------
// Chi-square quantile for the gate: the regularised lower incomplete gamma P(k/2, x/2) by its
// power series (Numerical Recipes, 3rd ed., sec. 6.2), inverted by bisection.

double ChiSquareCdf(double x, int dof) {
  if (x <= 0) return 0.0;
  const double a = 0.5 * dof, xx = 0.5 * x;
  double term = 1.0 / a, sum = term;
  for (int n = 1; n < 1000; ++n) {
    term *= xx / (a + n);
    sum += term;
    if (term < sum * 1e-16) break;
  }
  return sum * std::exp(-xx + a * std::log(xx) - std::lgamma(a));
}

double ChiSquareQuantile(double p, int dof) {
  double lo = 0.0, hi = 1000.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (ChiSquareCdf(mid, dof) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// ---------------------------------------------------------------------------------------------
// Start-up: skerry's course-over-ground start (docs/estimator.md, "Start-up", init.mode cog) in
// its plain-chord form: heading along the first fix -> the first fix at least
// min_cog_distance_m away horizontally (within max_cog_time_s), roll and pitch from the mean
// specific force over attitude_window_s, speed = chord / time, position = fix - R l.

struct InitialState {
  size_t imu_index;  // the first keyframe sits on this IMU sample
  gtsam::NavState state;
  gtsam::Vector6 pose_sigmas_w;  // roll/pitch/yaw about w's axes, then E, N, U
  double velocity_sigma;
};

InitialState CourseOverGroundStart(const Dataset& d, const Options& o) {
  const Fix& f0 = d.fixes.front();
  const bool has_heading = std::isfinite(f0.heading_rad) && d.fixes.size() > 1 &&
                           d.fixes[1].t - f0.t <= o.max_cog_time_s;
  const Fix* f1 = has_heading ? &d.fixes[1] : nullptr;
  for (const Fix& f : d.fixes) {
    if (f1 || f.t - f0.t > o.max_cog_time_s) break;
    if ((f.z - f0.z).head<2>().norm() >= o.min_cog_distance_m) {
      f1 = &f;
      break;
    }
  }
  if (!f1) throw std::runtime_error("start-up: no course over ground within max_cog_time_s");
  const Eigen::Vector2d chord = (f1->z - f0.z).head<2>();
  const double L = chord.norm(), T = f1->t - f0.t;
  // Yaw from east, counter-clockwise. init.mode auto: the dual-antenna heading when the first
  // fix has one (body heading = baseline heading + atan2(b_y, b_x), clockwise from north),
  // else the course over ground.
  const double yaw = has_heading
                         ? M_PI / 2 - (f0.heading_rad + std::atan2(d.baseline.y(), d.baseline.x()))
                         : std::atan2(chord.y(), chord.x());

  InitialState s;
  s.imu_index = std::lower_bound(d.imu.begin(), d.imu.end(), f0.t,
                                 [](const ImuSample& m, double t) { return m.t < t; }) -
                d.imu.begin();
  Vector3 f_mean = Vector3::Zero();
  int n = 0;
  for (size_t i = s.imu_index; i < d.imu.size() && d.imu[i].t < f0.t + o.attitude_window_s;
       ++i, ++n) {
    f_mean += d.imu[i].a;
  }
  const Vector3 f_b = d.T_b_i.rotation().matrix() * (f_mean / std::max(n, 1));
  // FLU body, ENU world, R_w_b = Rz(yaw) Ry(pitch) Rx(roll): f_b = R_w_b^T (0, 0, g).
  const double roll = std::atan2(f_b.y(), f_b.z());
  const double pitch = std::atan2(-f_b.x(), std::hypot(f_b.y(), f_b.z()));
  const Rot3 R = Rot3::Rz(yaw) * Rot3::Ry(pitch) * Rot3::Rx(roll);
  const Vector3 p = f0.z - R.matrix() * d.lever_arm;
  const Vector3 v = has_heading ? Vector3(chord.x() / T, chord.y() / T, 0.0)
                                : Vector3((L / T) * Vector3(std::cos(yaw), std::sin(yaw), 0.0));
  s.state = gtsam::NavState(R, p, v);
  // The chord's sigma, sqrt(2) sigma_h / L, combined with init.yaw_sigma_deg (crab, sideslip).
  const double sigma_h = std::max(f0.sigma.x(), f0.sigma.y());
  // heading: 3 x the receiver's sigma, at least 0.5 deg.
  const double yaw_sigma = has_heading
                               ? std::max(3.0 * f0.sigma_heading_rad, 0.5 * kDeg)
                               : std::hypot(std::sqrt(2.0) * sigma_h / L, o.yaw_sigma_deg * kDeg);
  const double rp = o.roll_pitch_sigma_deg * kDeg;
  s.pose_sigmas_w << rp, rp, yaw_sigma, o.position_sigma_scale * f0.sigma;
  s.velocity_sigma =
      has_heading ? std::hypot(o.velocity_sigma_m_s, 2.0 * sigma_h / T) : o.velocity_sigma_m_s;
  return s;
}

// ---------------------------------------------------------------------------------------------
// The smoothers behind one interface: update, estimate of the newest keys, and the joint
// covariance of (X, G) of one keyframe for the gate.

class Engine {
 public:
  virtual ~Engine() = default;
  virtual void Update(const gtsam::NonlinearFactorGraph& f,
                      const gtsam::Values& v,
                      const gtsam::FixedLagSmoother::KeyTimestampMap& ts) = 0;
  virtual gtsam::Values Estimate() const = 0;
  // Covariance over [pose tangent (6, GTSAM's: rotation then translation, body frame) | gb (3)].
  virtual Eigen::Matrix<double, 9, 9> PoseDriftCovariance(Key x, Key g) const = 0;
};

// The update and estimate of a GTSAM fixed-lag smoother (both smoothers share them).
template <typename Smoother>
class FixedLagEngine : public Engine {
 public:
  template <typename Params>
  FixedLagEngine(double lag, const Params& params) : smoother_(lag, params) {}
  void Update(const gtsam::NonlinearFactorGraph& f,
              const gtsam::Values& v,
              const gtsam::FixedLagSmoother::KeyTimestampMap& ts) override {
    smoother_.update(f, v, ts);
  }
  gtsam::Values Estimate() const override { return smoother_.calculateEstimate(); }

 protected:
  Smoother smoother_;
};

class Isam2Engine : public FixedLagEngine<gtsam::IncrementalFixedLagSmoother> {
 public:
  Isam2Engine(double lag, bool qr) : FixedLagEngine(lag, Params(qr)) {}
  static gtsam::ISAM2Params Params(bool qr) {
    gtsam::ISAM2Params p;  // Gauss-Newton steps, GTSAM's default relinearisation threshold 0.1
    // QR factors the Jacobian instead of forming the normal equations: it copes with the square
    // root of the dynamic range Cholesky must. With no integration noise (--integration-cov
    // 1e-12) the normal equations of a consumer IMU lose their positive definiteness near the
    // end of a 120 s outage (harbour-consumer; README, "iSAM2 and Cholesky").
    if (qr) p.factorization = gtsam::ISAM2Params::QR;
    p.relinearizeSkip = 1;  // check relinearisation at every update, as GTSAM's IMU examples
    p.findUnusedFactorSlots = true;  // fixed-lag: reuse the slots of marginalised factors
    return p;
  }
  Eigen::Matrix<double, 9, 9> PoseDriftCovariance(Key x, Key g) const override {
    // The joint marginal from the Bayes tree: the two variables' factor graph, whose
    // information inverts to their covariance.
    const gtsam::ISAM2& isam = smoother_.getISAM2();
    const auto joint = isam.joint(x, g);
    gtsam::Ordering ord;
    ord.push_back(x);
    ord.push_back(g);
    const Matrix info = joint->hessian(ord).first;
    return info.inverse();
  }
};

class BatchEngine : public FixedLagEngine<gtsam::BatchFixedLagSmoother> {
 public:
  BatchEngine(double lag, const Options& o) : FixedLagEngine(lag, Params(o)) {}
  static gtsam::LevenbergMarquardtParams Params(const Options& o) {
    gtsam::LevenbergMarquardtParams p;
    p.maxIterations = o.window_max_iterations;
    p.relativeErrorTol = o.window_tolerance;
    return p;
  }
  Eigen::Matrix<double, 9, 9> PoseDriftCovariance(Key x, Key g) const override {
    // BatchFixedLagSmoother::marginalCovariance is not implemented in GTSAM 4.3a0: the marginals
    // of the smoother's own graph (its marginal prior included) at its current estimate.
    gtsam::NonlinearFactorGraph graph;
    for (const auto& f : smoother_.getFactors()) {
      if (f) graph.push_back(f);
    }
    const gtsam::Marginals marginals(graph, smoother_.calculateEstimate());
    return marginals.jointMarginalCovariance({x, g}).fullMatrix();
  }
};

// ---------------------------------------------------------------------------------------------

struct Output {
  double t;
  Pose3 pose;
};

using Clock = std::chrono::steady_clock;

// Adds the wall time of its scope to *seconds.
class ScopedTimer {
 public:
  explicit ScopedTimer(double* seconds) : seconds_(seconds), start_(Clock::now()) {}
  ~ScopedTimer() { *seconds_ += std::chrono::duration<double>(Clock::now() - start_).count(); }
  ScopedTimer(const ScopedTimer&) = delete;
  ScopedTimer& operator=(const ScopedTimer&) = delete;

 private:
  double* seconds_;
  Clock::time_point start_;
};

struct RunStats {
  std::vector<double> keyframe_s;       // per keyframe: all of its work
  std::vector<double> keyframe_gate_s;  // per keyframe: of which the gate's covariance queries
  double update_s = 0;                  // the smoothers' update() calls
  double fix_update_s = 0;              // of which those adding accepted fixes (after the gate)
  double estimate_s = 0;                // reading the estimate back (calculateEstimate)
  double gate_s = 0;                    // the gate's covariance queries
  double gate_max_s = 0;                // the longest single query
  int smoother_updates = 0, gate_queries = 0;
  int accepted = 0, rejected = 0, reacquired = 0, dropped = 0;
  int heading_accepted = 0, heading_rejected = 0;
};

struct Run {
  std::vector<Output> outputs;
  RunStats stats;
  gtsam::NonlinearFactorGraph all_factors;  // every factor ever added (for batch-lm)
  gtsam::Values causal_values;              // every variable as it was when newest
  std::vector<double> keyframe_times;
};

// The causal pass: one keyframe at a time, in time order, through a fixed-lag smoother.
Run RunFixedLag(const Dataset& d, const Options& o, Engine* engine) {
  const Earth earth = EarthAtOrigin(d);
  auto params = std::make_shared<gtsam::PreintegrationCombinedParams>(earth.gravity_w);
  // Continuous-time densities squared (GTSAM discretises them by dt as skerry does, sigma^2 =
  // density^2 / dt: Forster eqs. 62-63).
  params->setGyroscopeCovariance(std::pow(d.gyro_nd, 2) * gtsam::I_3x3);
  params->setAccelerometerCovariance(std::pow(d.accel_nd, 2) * gtsam::I_3x3);
  // skerry has no integration noise; a small one keeps iSAM2's Cholesky factorable (Options).
  params->setIntegrationCovariance(o.integration_cov * gtsam::I_3x3);
  params->setBiasOmegaCovariance(std::pow(d.gyro_rw, 2) * gtsam::I_3x3);
  params->setBiasAccCovariance(std::pow(d.accel_rw, 2) * gtsam::I_3x3);
  // biasAccOmegaInt enters GTSAM's preintegration covariance as extra white noise (divided by
  // each step's dt); skerry's preintegration has no such term, and the bias priors are factors
  // on B(0) below, so it is zero here.
  params->setBiasAccOmegaInit(gtsam::Matrix6::Zero());
  params->setOmegaCoriolis(earth.omega_ie_w);
  params->setBodyPSensor(d.T_b_i);

  const double chi2_gate = ChiSquareQuantile(o.gate_probability, 3);
  const double chi2_gate_heading = ChiSquareQuantile(o.gate_probability, 1);
  const double period = 1.0 / o.keyframe_rate_hz;
  const InitialState init = CourseOverGroundStart(d, o);

  // Keyframes on IMU samples: the first at the start-up sample t0, then the first sample at or
  // past each t0 + n period (skerry's fixed grid, solvers/keyframe_policy.h: 0.06, 0.16, ...).
  std::vector<size_t> kf_index{init.imu_index};
  const double t_first = d.imu[init.imu_index].t;
  for (size_t i = init.imu_index + 1, n = 1; i < d.imu.size(); ++i) {
    if (d.imu[i].t >= t_first + n * period - 1e-9) {
      kf_index.push_back(i);
      ++n;
    }
  }

  Run run;
  const Vector3 drift_sigma(o.drift_sigma_h, o.drift_sigma_h, o.drift_sigma_v);
  gtsam::imuBias::ConstantBias bias;  // zero: the priors are about zero
  gtsam::NavState state = init.state;
  gtsam::PreintegratedCombinedMeasurements pim(params, bias);
  size_t next_fix = 0;
  double streak_start = -1, last_rejected = -1e300;
  RunStats& stats = run.stats;
  auto update = [&](const gtsam::NonlinearFactorGraph& f, const gtsam::Values& v,
                    const gtsam::FixedLagSmoother::KeyTimestampMap& ts) {
    const ScopedTimer timer(&stats.update_s);
    engine->Update(f, v, ts);
    ++stats.smoother_updates;
  };
  auto read_estimate = [&]() {
    const ScopedTimer timer(&stats.estimate_s);
    return engine->Estimate();
  };
  // What the smoother has not been given yet: the current keyframe, or with --update-every-fix
  // every keyframe since the last update.
  gtsam::NonlinearFactorGraph pending;
  gtsam::Values pending_values;
  gtsam::FixedLagSmoother::KeyTimestampMap pending_stamps;
  double last_update_t = -1e300;

  for (size_t k = 0; k < kf_index.size(); ++k) {
    const auto t0 = Clock::now();
    double gate_s = 0;  // this keyframe's covariance queries (a failed one included)
    const double t_k = d.imu[kf_index[k]].t;
    gtsam::NonlinearFactorGraph factors;
    gtsam::Values values;
    if (k == 0) {
      // Priors of the first state (skerry: init.* and the dataset's bias priors), GTSAM's
      // Pose3 tangent being body-frame: the world-frame sigmas turned by R^T.
      const Eigen::Matrix3d Rt = state.attitude().matrix().transpose();
      gtsam::Matrix6 cov = gtsam::Matrix6::Zero();
      cov.topLeftCorner<3, 3>() =
          Rt * init.pose_sigmas_w.head<3>().array().square().matrix().asDiagonal() * Rt.transpose();
      cov.bottomRightCorner<3, 3>() =
          Rt * init.pose_sigmas_w.tail<3>().array().square().matrix().asDiagonal() * Rt.transpose();
      factors.addPrior(X(0), state.pose(), gtsam::noiseModel::Gaussian::Covariance(cov));
      factors.addPrior(V(0), state.velocity(),
                       gtsam::noiseModel::Isotropic::Sigma(3, init.velocity_sigma));
      gtsam::Vector6 bias_sigmas;
      bias_sigmas << gtsam::Vector3::Constant(d.accel_prior),
          gtsam::Vector3::Constant(d.gyro_prior);
      factors.addPrior(B(0), bias, gtsam::noiseModel::Diagonal::Sigmas(bias_sigmas));
      factors.addPrior(G(0), Vector3(Vector3::Zero()),
                       gtsam::noiseModel::Diagonal::Sigmas(drift_sigma));
    } else {
      // Each step holds the average of two consecutive samples, the trapezoidal rule on the
      // measurements as skerry's preintegration (docs/estimator.md).
      for (size_t i = kf_index[k - 1]; i < kf_index[k]; ++i) {
        const ImuSample& a = d.imu[i];
        const ImuSample& b = d.imu[i + 1];
        pim.integrateMeasurement(0.5 * (a.a + b.a), 0.5 * (a.w + b.w), b.t - a.t);
      }
      factors.emplace_shared<gtsam::CombinedImuFactor>(X(k - 1), V(k - 1), X(k), V(k), B(k - 1),
                                                       B(k), pim);
      state = pim.predict(state, bias);
      const double dt = t_k - d.imu[kf_index[k - 1]].t;
      const double phi = std::exp(-dt / o.drift_tau_s);
      factors.emplace_shared<GaussMarkovDriftFactor>(
          G(k - 1), G(k), phi,
          gtsam::noiseModel::Diagonal::Sigmas(drift_sigma * std::sqrt(1.0 - phi * phi)));
    }
    values.insert(X(k), state.pose());
    values.insert(V(k), state.velocity());
    values.insert(B(k), bias);
    const Vector3 gb_prev =
        k == 0 ? Vector3(Vector3::Zero()) : run.causal_values.at<Vector3>(G(k - 1));
    values.insert(
        G(k),
        k == 0 ? gb_prev
               : Vector3(std::exp(-(t_k - run.keyframe_times.back()) / o.drift_tau_s) * gb_prev));
    for (Key key : {X(k), V(k), B(k), G(k)}) pending_stamps[key] = t_k;
    run.all_factors.push_back(factors);
    pending.push_back(factors);
    pending_values.insert(values);

    // The smoother takes the pending keyframes now: at every keyframe or, with
    // --update-every-fix, when a fix is due or a lag has passed without one (an outage: the
    // keyframes would otherwise leave the lag without ever being solved).
    const bool fix_due = next_fix < d.fixes.size() && d.fixes[next_fix].t <= t_k;
    const bool solve = !o.update_every_fix || fix_due || t_k - last_update_t >= o.lag_s - 1e-9;
    gtsam::Values estimate;
    if (solve) {
      update(pending, pending_values, pending_stamps);
      pending = gtsam::NonlinearFactorGraph();
      pending_values.clear();
      pending_stamps.clear();
      last_update_t = t_k;
      estimate = read_estimate();
    }
    // Fixes due now: those after the previous keyframe up to this one (from half a period before
    // the first), each tied to the nearer of the two keyframes (skerry: |dt| <= half a period).
    gtsam::NonlinearFactorGraph fix_factors;
    const double t_from = k == 0 ? t_k - 0.5 * period : run.keyframe_times.back();
    while (next_fix < d.fixes.size() && d.fixes[next_fix].t <= t_k) {
      const Fix& f = d.fixes[next_fix++];
      if (k == 0 && f.t < t_from) {  // more than half a period before the first state
        ++stats.dropped;
        continue;
      }
      const size_t kk = (k > 0 && f.t - run.keyframe_times.back() < t_k - f.t) ? k - 1 : k;
      const double t_kk = d.imu[kf_index[kk]].t;
      // skerry's TieFix: the lever arm and the baseline turned by the body's rotation over dt,
      // Exp(w_b dt), w_b = R_b_i (gyro - bg) - R_w_b^T w_ie with the gyro averaged over the 25 ms
      // up to the keyframe and the keyframe's current estimates.
      Vector3 gyro = Vector3::Zero();
      int n_gyro = 0;
      for (size_t i = kf_index[kk] + 1; i-- > 0 && d.imu[i].t > t_kk - 0.025;) {
        gyro += d.imu[i].w;
        ++n_gyro;
      }
      const Pose3 pose_kk = estimate.at<Pose3>(X(kk));
      const Vector3 w_b = d.T_b_i.rotation().matrix() *
                              (gyro / std::max(n_gyro, 1) -
                               estimate.at<gtsam::imuBias::ConstantBias>(B(kk)).gyroscope()) -
                          pose_kk.rotation().matrix().transpose() * earth.omega_ie_w;
      const Rot3 turn = Rot3::Expmap(w_b * (f.t - t_kk));
      const Vector3 lever_arm = turn * d.lever_arm;
      const Vector3 baseline = turn * d.baseline;
      const Eigen::Matrix3d sqrt_info = f.sigma.cwiseInverse().asDiagonal() * f.R_w_n.transpose();
      const auto gaussian = gtsam::noiseModel::Gaussian::SqrtInformation(sqrt_info);
      LeverArmGnssFactor plain(X(kk), V(kk), G(kk), f.z, lever_arm, f.t - t_kk, gaussian);
      // The innovation gate (Bar-Shalom et al. 2001, sec. 5.4.2; skerry's BlockInnovation):
      // whitened r and J over (pose, gb) at the current estimate, S = J P J^T + I,
      // d^2 = r^T S^-1 r against chi^2_3(p). The velocity's share (dt <= 50 ms) is left out.
      std::vector<Matrix> H(3);
      const gtsam::Vector r_raw = plain.unwhitenedError(estimate, H);
      Eigen::Matrix<double, 3, 9> J;
      J << sqrt_info * H[0], sqrt_info * H[2];
      const Vector3 r = sqrt_info * r_raw;
      bool accept = true, reacquired = false;
      Eigen::Matrix<double, 9, 9> P;
      P.setConstant(NAN);
      try {
        double query_s = 0;
        {
          const ScopedTimer timer(&query_s);
          ++stats.gate_queries;
          P = engine->PoseDriftCovariance(X(kk), G(kk));
        }
        gate_s += query_s;
        stats.gate_max_s = std::max(stats.gate_max_s, query_s);
        const Eigen::Matrix3d S = J * P * J.transpose() + Eigen::Matrix3d::Identity();
        const double d2 = r.dot(S.ldlt().solve(r));
        accept = !(d2 > chi2_gate);  // a NaN covariance gates nothing, as in skerry
      } catch (const std::exception&) {
        accept = true;  // a covariance that cannot be computed gates nothing
      }
      if (!accept) {
        // A rejection streak is broken by an accepted fix or a gap > gate_streak_max_gap_s;
        // after gate_max_reject_s of it the fix is taken (re-acquisition, simplified: skerry
        // also re-initialises its window with an inflated covariance, see README).
        if (streak_start < 0 || f.t - last_rejected > o.gate_streak_max_gap_s) streak_start = f.t;
        last_rejected = f.t;
        if (f.t - streak_start > o.gate_max_reject_s) {
          accept = reacquired = true;
          streak_start = -1;
        }
      } else {
        streak_start = -1;
      }
      if (!accept) {
        ++stats.rejected;
        continue;
      }
      reacquired ? ++stats.reacquired : ++stats.accepted;
      const auto robust = gtsam::noiseModel::Robust::Create(
          gtsam::noiseModel::mEstimator::Huber::Create(o.huber_k), gaussian);
      fix_factors.emplace_shared<LeverArmGnssFactor>(X(kk), V(kk), G(kk), f.z, lever_arm,
                                                     f.t - t_kk, robust);
      // The heading of an accepted fix (gnss.use_heading), gated alone against chi^2_1(p) with
      // the pose's covariance.
      if (!std::isfinite(f.heading_rad)) continue;
      const auto heading_noise = gtsam::noiseModel::Isotropic::Sigma(1, f.sigma_heading_rad);
      GnssHeadingFactor heading(X(kk), f.heading_rad, baseline, f.R_w_n.transpose(), heading_noise);
      std::vector<Matrix> Hh(1);
      const double rh = heading.unwhitenedError(estimate, Hh)(0) / f.sigma_heading_rad;
      const Eigen::Matrix<double, 1, 6> Jh = Hh[0] / f.sigma_heading_rad;
      const double Sh = (Jh * P.topLeftCorner<6, 6>() * Jh.transpose())(0) + 1.0;
      if (rh * rh / Sh > chi2_gate_heading) {  // NaN (no covariance) gates nothing
        ++stats.heading_rejected;
        continue;
      }
      ++stats.heading_accepted;
      fix_factors.emplace_shared<GnssHeadingFactor>(
          X(kk), f.heading_rad, baseline, f.R_w_n.transpose(),
          gtsam::noiseModel::Robust::Create(gtsam::noiseModel::mEstimator::Huber::Create(o.huber_k),
                                            heading_noise));
    }
    if (!fix_factors.empty()) {
      run.all_factors.push_back(fix_factors);
      {
        const ScopedTimer timer(&stats.fix_update_s);
        update(fix_factors, gtsam::Values(), {});
      }
      estimate = read_estimate();
    }
    // The keyframe as it is now: solved, or (--update-every-fix, between fixes) predicted by the
    // IMU from the last solution, as skerry's window between its solves.
    Vector3 gb = values.at<Vector3>(G(k));
    if (solve) {
      state = gtsam::NavState(estimate.at<Pose3>(X(k)), estimate.at<Vector3>(V(k)));
      bias = estimate.at<gtsam::imuBias::ConstantBias>(B(k));
      gb = estimate.at<Vector3>(G(k));
    }
    pim.resetIntegrationAndSetBias(bias);
    run.outputs.push_back({t_k, state.pose()});
    run.causal_values.insert(X(k), state.pose());
    run.causal_values.insert(V(k), state.velocity());
    run.causal_values.insert(B(k), bias);
    run.causal_values.insert(G(k), gb);
    run.keyframe_times.push_back(t_k);
    stats.gate_s += gate_s;
    stats.keyframe_gate_s.push_back(gate_s);
    stats.keyframe_s.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
  }
  return run;
}

void WriteTum(const std::string& path, const std::vector<Output>& outputs) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error(path + ": cannot write");
  std::fprintf(f, "# t x y z qx qy qz qw (gtsam_peer: body pose T_w_b in local ENU)\n");
  for (const Output& o : outputs) {
    const gtsam::Quaternion q = o.pose.rotation().toQuaternion();
    const Vector3 p = o.pose.translation();
    std::fprintf(f, "%.9f %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", o.t, p.x(), p.y(), p.z(),
                 q.x(), q.y(), q.z(), q.w());
  }
  std::fclose(f);
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double pos = p * (v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - lo) * (v[hi] - v[lo]);
}

int ThreadCount() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("Threads:", 0) == 0) return std::stoi(line.substr(8));
  }
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    o = ParseArgs(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "gtsam_peer: " << e.what() << "\n";
    Usage();
    return 2;
  }
  try {
    const Dataset d = LoadDataset(o.dataset);  // file reading: outside the estimator time

    std::unique_ptr<Engine> engine;
    if (o.mode == "batch-fixed-lag") {
      engine = std::make_unique<BatchEngine>(o.lag_s, o);
    } else {
      engine =
          std::make_unique<Isam2Engine>(o.lag_s, o.isam2_qr);  // isam2, and batch-lm's first pass
    }
    Run run = RunFixedLag(d, o, engine.get());
    engine.reset();
    const RunStats& st = run.stats;
    double pass_s = 0;
    for (double s : st.keyframe_s) pass_s += s;

    std::ostringstream extra;
    double estimator_s = pass_s;
    if (o.mode == "batch-lm") {
      // The whole run in one Levenberg-Marquardt solve (skerry smooth's batch_solver: LM, 50
      // iterations), started from the causal pass; the accepted fixes are the causal pass's.
      const auto t0 = std::chrono::steady_clock::now();
      gtsam::LevenbergMarquardtParams p;
      p.maxIterations = o.batch_max_iterations;
      p.relativeErrorTol = o.window_tolerance;
      gtsam::LevenbergMarquardtOptimizer lm(run.all_factors, run.causal_values, p);
      const double error0 = lm.error();
      const gtsam::Values result = lm.optimize();
      const double lm_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      for (size_t k = 0; k < run.outputs.size(); ++k) {
        run.outputs[k].pose = result.at<Pose3>(X(k));
      }
      estimator_s += lm_s;
      extra << ",\"init_pass_s\":" << pass_s << ",\"lm_s\":" << lm_s
            << ",\"lm_iterations\":" << lm.iterations() << ",\"lm_error_start\":" << error0
            << ",\"lm_error_end\":" << lm.error();
    }
    WriteTum(o.out_tum, run.outputs);

    struct rusage ru {};
    getrusage(RUSAGE_SELF, &ru);
    const std::vector<double>& u = st.keyframe_s;
    std::vector<double> u_nogate(u.size());
    for (size_t k = 0; k < u.size(); ++k) u_nogate[k] = u[k] - st.keyframe_gate_s[k];
    const double ms = 1e3;
    std::ostringstream js;
    js.precision(6);
    js << "{\"mode\":\"" << o.mode << "\",\"update_on\":\""
       << (o.update_every_fix ? "fix" : "keyframe") << "\",\"factorization\":\""
       << (o.mode == "batch-fixed-lag" ? "lm-cholesky"
           : o.isam2_qr                ? "qr"
                                       : "cholesky")
       << "\",\"integration_cov\":" << o.integration_cov << ",\"lag_s\":" << o.lag_s
       << ",\"keyframes\":" << u.size() << ",\"estimator_s\":" << estimator_s
       << ",\"update_s\":" << st.update_s << ",\"fix_update_s\":" << st.fix_update_s
       << ",\"estimate_s\":" << st.estimate_s << ",\"gate_s\":" << st.gate_s
       << ",\"other_s\":" << pass_s - st.update_s - st.estimate_s - st.gate_s
       << ",\"smoother_updates\":" << st.smoother_updates << ",\"gate_queries\":" << st.gate_queries
       << ",\"gate_mean_ms\":" << ms * st.gate_s / std::max(st.gate_queries, 1)
       << ",\"gate_max_ms\":" << ms * st.gate_max_s
       << ",\"keyframe_mean_ms\":" << ms * pass_s / std::max<size_t>(u.size(), 1)
       << ",\"keyframe_median_ms\":" << ms * Percentile(u, 0.5)
       << ",\"keyframe_p95_ms\":" << ms * Percentile(u, 0.95)
       << ",\"keyframe_max_ms\":" << ms * Percentile(u, 1.0)
       << ",\"keyframe_nogate_p95_ms\":" << ms * Percentile(u_nogate, 0.95)
       << ",\"keyframe_nogate_max_ms\":" << ms * Percentile(u_nogate, 1.0)
       << ",\"threads\":" << ThreadCount() << ",\"peak_rss_mb\":" << ru.ru_maxrss / 1024.0
       << ",\"fixes_accepted\":" << st.accepted << ",\"fixes_rejected\":" << st.rejected
       << ",\"fixes_reacquired\":" << st.reacquired << ",\"fixes_dropped\":" << st.dropped
       << ",\"headings_accepted\":" << st.heading_accepted
       << ",\"headings_rejected\":" << st.heading_rejected << extra.str() << "}";
    std::cout << js.str() << std::endl;
    if (!o.json.empty()) {
      std::ofstream(o.json) << js.str() << "\n";
    }
    return 0;
  } catch (const std::exception& e) {  // e.g. GTSAM's IndeterminantLinearSystemException
    std::cerr << "gtsam_peer: " << e.what() << "\n";
    return 1;
  }
}
