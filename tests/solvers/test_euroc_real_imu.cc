// skerry on the real EuRoC MAV V1_01_easy IMU (ADIS16448, 200 Hz) against the Vicon ground
// truth: IMU preintegration over 1 s, and fusion with position fixes made from the truth.
// The figures come from examples/euroc/euroc_figures.h, the same code that
// ./build/tests/solvers/euroc_report prints (see examples/euroc/README.md for the measured
// values). Skipped when ../shared/data/euroc_v1_01 is missing.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "euroc_figures.h"
#include "skerry/io/importers.h"

namespace skerry {
namespace {

using euroc::Quantile;

const std::string kEurocDir = std::string(SKERRY_SHARED_DATA_DIR) + "/euroc_v1_01";

class EurocRealImu : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (std::filesystem::exists(kEurocDir + "/imu0_data.csv")) {
      data_ = new Dataset(ImportEuroc(kEurocDir));
    }
  }
  static void TearDownTestSuite() {
    delete data_;
    data_ = nullptr;
  }
  void SetUp() override {
    if (data_ == nullptr) GTEST_SKIP() << "no EuRoC data at " << kEurocDir;
  }
  static Dataset* data_;
};

Dataset* EurocRealImu::data_ = nullptr;

// EuRoC's truth velocity is in the world (Vicon) frame: it matches the central difference of
// the truth positions to millimetres per second, and is far off when read as body-frame.
TEST_F(EurocRealImu, TruthVelocityIsWorldFrame) {
  const euroc::VelocityFrameCheck check = euroc::CheckTruthVelocityFrame(data_->truth_states);
  EXPECT_GT(check.count, 2500);
  EXPECT_LT(check.rms_world_m_s, 0.02);
  EXPECT_GT(check.rms_body_m_s, 10.0 * check.rms_world_m_s);
}

// Predict the truth state 1 s ahead through the real IMU, one interval per truth sample.
//
// Bounds, from the sensor model and what the data show (measured: rotation median 0.104 deg,
// velocity median 0.045 m/s, position median 0.023 m):
//  - gyro white noise (1.7e-4 rad/s/sqrt(Hz)) alone gives ~0.01 deg over 1 s; the measured error
//    grows linearly with the interval (0.006 deg at 50 ms, 0.10 deg at 1 s, 0.18 deg at 2 s), a
//    time-correlated rate error of ~0.1 deg/s between the gyro and the truth attitude with its
//    bias estimate, not white noise, and not a time offset or a scale/misalignment (fitting either
//    leaves it at 0.09-0.10 deg). Bound 0.15 deg: 1.5x margin; a frame or bias-sign error costs
//    degrees.
//  - accelerometer white noise (2e-3 m/s^2/sqrt(Hz)) alone gives ~2e-3 m/s over 1 s; the
//    measured error is dominated by a constant world-frame bias of +0.040 m/s per second along
//    Vicon x (mean signed error; it grows linearly with the interval and does not turn with the
//    vehicle), i.e. the Vicon z axis is ~0.24 deg off the gravity direction. Bound 0.06 m/s
//    covers that with margin; a mishandled gravity or frame gives metres per second.
//  - position: half the velocity error times 1 s, bound 0.04 m.
TEST_F(EurocRealImu, PreintegrationOverOneSecondMatchesTruth) {
  const euroc::PreintegrationFigures f = euroc::MeasurePreintegration(*data_);
  ASSERT_GT(f.rot_err_deg.size(), 2800u);  // 144 s of truth at 20 Hz
  EXPECT_LT(f.max_end_offset_s, 0.0026);   // interval ends on IMU samples, truth interpolated
  EXPECT_LT(Quantile(f.rot_err_deg, 0.5), 0.15);
  EXPECT_LT(Quantile(f.rot_err_deg, 0.9), 0.3);
  EXPECT_LT(Quantile(f.vel_err_m_s, 0.5), 0.06);
  EXPECT_LT(Quantile(f.vel_err_m_s, 0.9), 0.09);
  EXPECT_LT(Quantile(f.pos_err_m, 0.5), 0.04);
  // The gravity-tilt signature, predicted from data the preintegration does not use: at rest
  // (the MAV stands still for its first 4 s) the specific force rotated into the Vicon frame by
  // the truth attitude is minus gravity there; the model's gravity is (0, 0, -g), so a prediction
  // over 1 s is off by (0, 0, -g) + f_w, a horizontal error of g times the Vicon frame's tilt.
  Eigen::Vector3d f_w = Eigen::Vector3d::Zero();
  int n = 0;
  const TimeNs t_rest_end = data_->imu_samples.front().t_ns + SecondsToNs(3.5);
  for (const ImuSample& s : data_->imu_samples) {
    if (s.t_ns > t_rest_end) break;
    NavState truth;
    if (!euroc::InterpolateTruth(data_->truth_states, s.t_ns, &truth)) continue;
    f_w += truth.q_w_b * (data_->imu.q_b_i * (s.accel_m_s2 - truth.ba));
    ++n;
  }
  ASSERT_GT(n, 600);
  f_w /= n;
  std::printf(
      "tilt of the Vicon frame from gravity: %.3f deg; predicted drift (%.4f, %.4f) m/s "
      "per s, measured (%.4f, %.4f)\n",
      std::atan2(f_w.head<2>().norm(), f_w.z()) * 180.0 / M_PI, f_w.x(), f_w.y(),
      f.mean_vel_err_w.x(), f.mean_vel_err_w.y());
  EXPECT_GT(f_w.head<2>().norm(), 0.02);  // a real tilt, 0.2 deg and more
  EXPECT_NEAR(f.mean_vel_err_w.x(), f_w.x(), 0.006);
  EXPECT_NEAR(f.mean_vel_err_w.y(), f_w.y(), 0.006);
}

// Fusion of the real IMU with truth-made fixes (2 Hz, 0.5 m white noise), started from the
// truth state with the attitude off by (2, -2, 5) deg about (E, N, U) and a 10 deg prior, truth
// biases with the dataset's bias prior sigmas; scored after 10 s. Roll and pitch are recovered
// (measured 0.37 deg RMS, of which ~0.24 deg is the Vicon frame's tilt from gravity).
TEST_F(EurocRealImu, FusionRecoversRollPitchBelowOneDegree) {
  const euroc::FusionFigures f = euroc::MeasureFusion(*data_, LoadPreset("default"));
  EXPECT_EQ(f.gnss.accepted, f.fixes);
  EXPECT_GT(f.epochs, 1300);
  EXPECT_LT(f.rms_tilt_deg, 1.0);
  EXPECT_LT(f.rms_pos_m, 1.0);
}

// Heading. The issue asks for the whole attitude to better than 1 deg RMS; on this data the
// heading is not (window 4.97 deg RMS, measured) and cannot be: heading shows in position fixes
// only through horizontal acceleration, which V1_01 has little of. The batch smoother over the
// whole recording, the best any estimator with this model can do, has a yaw 1-sigma of 2.66 deg
// RMS (yaw error 2.11 deg). So this test asserts what can be asserted: the information bound is
// above 1 deg, the batch reaches it, and the window's heading error is what its own covariance
// says (yaw ANEES 0.99, sigma 4.94 deg: neither overconfident, which would reject good fixes, nor
// uselessly loose), under ceilings that keep a loose sigma from passing. See
// examples/euroc/README.md.
TEST_F(EurocRealImu, HeadingIsAtTheDataBoundAndConsistent) {
  const euroc::FusionFigures f = euroc::MeasureFusion(*data_, LoadPreset("default"));
  ASSERT_TRUE(f.batch_usable);
  EXPECT_GT(f.batch_rms_yaw_sigma_deg, 1.0);  // 1 deg heading is not in these data
  EXPECT_LT(f.batch_rms_yaw_deg, 1.5 * f.batch_rms_yaw_sigma_deg);
  EXPECT_LT(f.batch_rms_yaw_deg, f.rms_yaw_deg);  // the batch is at least as accurate
  EXPECT_LT(f.batch_rms_tilt_deg, 1.0);
  EXPECT_GT(f.anees_yaw, 0.2);
  EXPECT_LT(f.anees_yaw, 2.0);
  EXPECT_LT(f.rms_yaw_deg, 2.0 * f.rms_yaw_sigma_deg);
  EXPECT_LT(f.rms_yaw_deg, 8.0);        // measured 4.97
  EXPECT_LT(f.rms_yaw_sigma_deg, 8.0);  // measured 4.94
}

// No given first state: heading and gyro bias unknown (truth gyro bias 0.077 rad/s about the
// vertical, 75x the dataset's prior sigma). init.mode "align" with the 4 s the MAV stands still
// before take-off: the rest period gives the gyro bias and the tilt, the yaw-hypothesis bank the
// heading (measured: decision 43 s in, yaw 10.6 deg RMS after 10 s with a 6.3 deg sigma, yaw
// ANEES 2.5, tilt 0.40 deg, every fix accepted; examples/euroc/README.md). Without it the window
// cannot start at all (no course over ground: the MAV moves a few metres) or, from zero biases,
// runs 90 deg off.
TEST_F(EurocRealImu, AlignFromRestFindsGyroBiasAndHeading) {
  euroc::FusionOptions options;
  options.align_static_s = 4.0;
  options.with_batch = false;
  const euroc::FusionFigures f = euroc::MeasureFusion(*data_, LoadPreset("default"), options);
  EXPECT_EQ(f.gnss.accepted, f.fixes);
  EXPECT_GT(f.epochs, 1300);
  EXPECT_LT(f.rms_tilt_deg, 1.0);
  // The heading error is what its own sigma says (one noise draw of the fixes: no fixed bound).
  EXPECT_LT(f.rms_yaw_deg, 2.0 * f.rms_yaw_sigma_deg);
  EXPECT_GT(f.anees_yaw, 0.2);
  EXPECT_LT(f.anees_yaw, 3.0);
  EXPECT_LT(f.rms_yaw_deg, 15.0);        // measured 10.6
  EXPECT_LT(f.rms_yaw_sigma_deg, 12.0);  // measured 6.3
  EXPECT_LT(f.rms_pos_m, 1.0);
  // The rest period's gyro mean against the truth bias at the start (1.3e-3 rad/s from the raw
  // data).
  EXPECT_LT((f.first_bg - data_->truth_states.front().bg).norm(), 0.003);
}

}  // namespace
}  // namespace skerry
