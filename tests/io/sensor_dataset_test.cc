// The dataset format's sensors beyond IMU and GNSS (pose fixes, cameras, LiDARs) and its maps:
// what loads, what round-trips, and the errors that name file, line and key.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/test_util.h"
#include "io/dataset_folder_test.h"
#include "skerry/io/dataset.h"

namespace skerry {
namespace {

using testing::ExpectInputError;
using testing::FreshDir;
using testing::ReadLines;
using testing::WriteLines;
using testing::WriteText;

constexpr char kYaml[] = R"(name: sensors
origin: {lat_deg: 43.6, lon_deg: 7.2, height_m: 50.0}
sensors:
  imu:
    file: imu.csv
    rate_hz: 200
    T_b_i: {q_xyzw: [0, 0, 0, 1], p_m: [0, 0, 0]}
    gyro_noise_density_rad_s_sqrt_hz: 1.7e-4
    accel_noise_density_m_s2_sqrt_hz: 2.0e-3
    gyro_bias_random_walk_rad_s2_sqrt_hz: 2.0e-5
    accel_bias_random_walk_m_s3_sqrt_hz: 3.0e-3
  pose_fixes:
    file: pose_fixes.csv
    T_b_s: {q_xyzw: [0, 0, 0.7071067811865476, 0.7071067811865476], p_m: [2.0, 0.0, 1.5]}
  camera_bow:
    images: images
    file: camera.csv
    width_px: 640
    height_px: 480
    fx: 500
    fy: 500
    cx: 320
    cy: 240
    distortion: [-0.1, 0.01, 0.0, 0.0, 0.0]
    T_b_c: {q_xyzw: [0.5, -0.5, 0.5, -0.5], p_m: [3.0, 0.0, 2.0]}
  water_surface: {height_m: 51.2, sigma_m: 0.25, rate_hz: 2}
  lidar:
    scans: scans
    file: lidar.csv
    T_b_l: {q_xyzw: [0, 0, 0, 1], p_m: [0.0, 0.0, 3.0]}
maps:
  dem: {file: dem.hgt, vertical_datum: egm96}
  orthophoto: {file: ortho.tif, crs: "EPSG:32632", viewpoint: {lat_deg: 47.6, lon_deg: 9.45, height_m: 1240.5}, clip_fraction: 0.01}
)";

constexpr char kPoseFixHeader[] =
    "t,kind,east,north,up,heading_deg,cov_ee,cov_en,cov_eu,cov_eh,cov_nn,cov_nu,cov_nh,cov_uu,"
    "cov_uh,cov_hh";

class SensorDatasetTest : public testing::DatasetFolderTest {
 protected:
  void SetUp() override {
    MakeDir("sensor_dataset_");
    WriteText(dir_ + "/dataset.yaml", kYaml);
    WriteText(dir_ + "/imu.csv", "t,wx,wy,wz,ax,ay,az\n0.0,0,0,0,0,0,9.8\n0.005,0,0,0,0,0,9.8\n");
    WriteText(dir_ + "/pose_fixes.csv", std::string(kPoseFixHeader) +
                                            "\n"
                                            "0.25,enh,10,20,0,45,0.25,0.05,0,0.1,0.25,0,0,1,0,1\n"
                                            "1.25,en,11,21,0,0,0.25,0,0,0,0.25,0,0,0,0,0\n"
                                            "2.25,enuh,12,22,1,90,1,0,0,0,1,0,0,4,0,2\n");
    std::filesystem::create_directories(dir_ + "/images");
    std::filesystem::create_directories(dir_ + "/scans");
    WriteText(dir_ + "/images/a.png", "x");
    WriteText(dir_ + "/images/b.png", "x");
    WriteText(dir_ + "/scans/a.pcd", "x");
    WriteText(dir_ + "/camera.csv", "t,file\n0.1,a.png\n0.2,b.png\n");
    WriteText(dir_ + "/lidar.csv", "t,file\n0.1,a.pcd\n");
    WriteText(dir_ + "/dem.hgt", "x");
    WriteText(dir_ + "/ortho.tif", "x");
  }
};

TEST_F(SensorDatasetTest, Loads) {
  const Dataset d = LoadDataset(dir_);
  ASSERT_TRUE(d.has_pose_fixes);
  ASSERT_EQ(d.pose_fixes.size(), 3u);
  const PoseFix& f = d.pose_fixes[0];
  EXPECT_EQ(f.t_ns, 250'000'000);
  EXPECT_FALSE(f.has_up);
  EXPECT_TRUE(f.has_heading);
  EXPECT_DOUBLE_EQ(f.heading_deg, 45.0);
  // Heading variances are deg^2 in the file, rad^2 inside; cross terms m deg -> m rad.
  const double d2r = M_PI / 180.0;
  EXPECT_NEAR(f.covariance(3, 3), d2r * d2r, 1e-15);
  EXPECT_NEAR(f.covariance(0, 3), 0.1 * d2r, 1e-15);
  EXPECT_DOUBLE_EQ(f.covariance(1, 0), 0.05);
  EXPECT_TRUE(d.pose_fixes[2].has_up && d.pose_fixes[2].has_heading);
  EXPECT_NEAR(d.pose_fix_mount.p_b_s.x(), 2.0, 1e-15);
  EXPECT_NEAR(d.pose_fix_mount.q_b_s.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()))),
              0.0, 1e-12);

  ASSERT_EQ(d.cameras.size(), 1u);
  EXPECT_EQ(d.cameras[0].name, "camera_bow");
  EXPECT_EQ(d.cameras[0].width_px, 640);
  EXPECT_EQ(d.cameras[0].distortion.size(), 5u);
  ASSERT_EQ(d.camera_frames.at(0).size(), 2u);
  EXPECT_EQ(d.camera_frames[0][1].file, "b.png");
  ASSERT_EQ(d.lidars.size(), 1u);
  EXPECT_NEAR(d.lidars[0].T_b_l.p_b_s.z(), 3.0, 1e-15);
  ASSERT_TRUE(d.water_surface.has_value());
  EXPECT_DOUBLE_EQ(d.water_surface->height_m, 51.2);
  EXPECT_DOUBLE_EQ(d.water_surface->rate_hz, 2.0);
  ASSERT_TRUE(d.dem.has_value());
  EXPECT_EQ(d.dem->vertical_datum, "egm96");
  ASSERT_TRUE(d.orthophoto.has_value());
  EXPECT_EQ(d.orthophoto->crs, "EPSG:32632");
  ASSERT_TRUE(d.orthophoto->viewpoint.has_value());
  EXPECT_DOUBLE_EQ(d.orthophoto->viewpoint->height_m, 1240.5);
  EXPECT_FALSE(d.dem->viewpoint.has_value());
  EXPECT_EQ(d.orthophoto->clip_fraction, 0.01);
  EXPECT_FALSE(d.dem->clip_fraction.has_value());
}

TEST_F(SensorDatasetTest, RoundTrip) {
  const Dataset d = LoadDataset(dir_);
  const std::string out = FreshDir("sensor_dataset_round_trip_out");
  WriteDataset(d, out);
  const Dataset e = LoadDataset(out);
  ASSERT_EQ(e.pose_fixes.size(), d.pose_fixes.size());
  for (size_t k = 0; k < d.pose_fixes.size(); ++k) {
    EXPECT_EQ(e.pose_fixes[k].t_ns, d.pose_fixes[k].t_ns);
    EXPECT_EQ(e.pose_fixes[k].MeasuredComponents(), d.pose_fixes[k].MeasuredComponents());
    EXPECT_TRUE(e.pose_fixes[k].p_w.isApprox(d.pose_fixes[k].p_w, 1e-15));
    EXPECT_LT((e.pose_fixes[k].covariance - d.pose_fixes[k].covariance).cwiseAbs().maxCoeff(),
              1e-15);
  }
  EXPECT_NEAR(e.pose_fix_mount.p_b_s.x(), 2.0, 1e-15);
  ASSERT_EQ(e.cameras.size(), 1u);
  EXPECT_EQ(e.camera_frames[0].size(), 2u);
  EXPECT_EQ(e.cameras[0].distortion, d.cameras[0].distortion);
  ASSERT_EQ(e.lidar_scans.size(), 1u);
  ASSERT_TRUE(e.water_surface.has_value());
  EXPECT_DOUBLE_EQ(e.water_surface->sigma_m, 0.25);
  ASSERT_TRUE(e.dem && e.orthophoto);
  EXPECT_EQ(e.dem->vertical_datum, "egm96");
  ASSERT_TRUE(e.orthophoto->viewpoint.has_value());
  EXPECT_EQ(e.orthophoto->viewpoint->lat_deg, d.orthophoto->viewpoint->lat_deg);
  EXPECT_EQ(e.orthophoto->viewpoint->lon_deg, d.orthophoto->viewpoint->lon_deg);
  EXPECT_EQ(e.orthophoto->viewpoint->height_m, d.orthophoto->viewpoint->height_m);
  EXPECT_EQ(e.orthophoto->clip_fraction, d.orthophoto->clip_fraction);
}

TEST_F(SensorDatasetTest, OrthophotoViewpointOutOfRange) {
  ReplaceLine("dataset.yaml", 33,
              "  orthophoto: {file: ortho.tif, viewpoint: {lat_deg: 95, lon_deg: 9, height_m: 1}}");
  ExpectError("dataset.yaml", 33, "maps.orthophoto.viewpoint.lat_deg");
}

TEST_F(SensorDatasetTest, OrthophotoClipFractionOutOfRange) {
  for (const char* clip : {"0.5", "-0.01", ".nan", "lots"}) {
    ReplaceLine("dataset.yaml", 33,
                std::string("  orthophoto: {file: ortho.tif, clip_fraction: ") + clip + "}");
    ExpectError("dataset.yaml", 33, "maps.orthophoto.clip_fraction");
  }
  ReplaceLine("dataset.yaml", 32,
              "  dem: {file: dem.hgt, vertical_datum: egm96, clip_fraction: 0}");
  ExpectError("dataset.yaml", 32, "maps.dem.clip_fraction");
}

TEST_F(SensorDatasetTest, OrthophotoViewpointMissingHeight) {
  ReplaceLine("dataset.yaml", 33,
              "  orthophoto: {file: ortho.tif, viewpoint: {lat_deg: 47, lon_deg: 9}}");
  ExpectError("dataset.yaml", 33, "maps.orthophoto.viewpoint.height_m");
}

TEST_F(SensorDatasetTest, PoseFixCovarianceNotPositiveDefinite) {
  // cov_en^2 > cov_ee cov_nn.
  ReplaceLine("pose_fixes.csv", 3, "1.25,en,11,21,0,0,0.25,0.5,0,0,0.25,0,0,0,0,0");
  ExpectError("pose_fixes.csv", 3, "cov_ee");
}

TEST_F(SensorDatasetTest, PoseFixZeroHeadingVariance) {
  ReplaceLine("pose_fixes.csv", 2, "0.25,enh,10,20,0,45,0.25,0,0,0,0.25,0,0,1,0,0");
  ExpectError("pose_fixes.csv", 2, "cov_ee");
}

TEST_F(SensorDatasetTest, PoseFixUnknownKind) {
  ReplaceLine("pose_fixes.csv", 2, "0.25,xyz,10,20,0,45,0.25,0,0,0,0.25,0,0,1,0,1");
  ExpectError("pose_fixes.csv", 2, "kind");
}

TEST_F(SensorDatasetTest, PoseFixNaN) {
  ReplaceLine("pose_fixes.csv", 4, "2.25,enuh,12,nan,1,90,1,0,0,0,1,0,0,4,0,2");
  ExpectError("pose_fixes.csv", 4, "north");
}

TEST_F(SensorDatasetTest, PoseFixTimeGoesBack) {
  ReplaceLine("pose_fixes.csv", 4, "1.0,enuh,12,22,1,90,1,0,0,0,1,0,0,4,0,2");
  ExpectError("pose_fixes.csv", 4, "t");
}

TEST_F(SensorDatasetTest, PoseFixMissingMount) {
  ReplaceLine("dataset.yaml", 14, "    lever_arm_m: [2.0, 0.0, 1.5]");
  ExpectError("dataset.yaml", 14, "sensors.pose_fixes.lever_arm_m");
}

TEST_F(SensorDatasetTest, CameraMissingFocalLength) {
  ReplaceLine("dataset.yaml", 20, "    fz: 500");
  ExpectError("dataset.yaml", 20, "sensors.camera_bow.fz");
}

TEST_F(SensorDatasetTest, CameraImageMissing) {
  ReplaceLine("camera.csv", 3, "0.2,c.png");
  ExpectError("camera.csv", 3, "file");
}

TEST_F(SensorDatasetTest, CameraBadDistortion) {
  ReplaceLine("dataset.yaml", 24, "    distortion: [-0.1, 0.01, 0.0]");
  ExpectError("dataset.yaml", 24, "sensors.camera_bow.distortion");
}

TEST_F(SensorDatasetTest, LidarFolderMissing) {
  ReplaceLine("dataset.yaml", 28, "    scans: no_such_folder");
  ExpectError("dataset.yaml", 28, "sensors.lidar.scans");
}

TEST_F(SensorDatasetTest, DemWithoutVerticalDatum) {
  ReplaceLine("dataset.yaml", 32, "  dem: {file: dem.hgt}");
  ExpectError("dataset.yaml", 32, "maps.dem.vertical_datum");
}

TEST_F(SensorDatasetTest, DemFileMissing) {
  ReplaceLine("dataset.yaml", 32, "  dem: {file: nowhere.hgt, vertical_datum: egm96}");
  ExpectError("dataset.yaml", 32, "maps.dem.file");
}

TEST_F(SensorDatasetTest, WaterSurfaceWithoutSigma) {
  ReplaceLine("dataset.yaml", 26, "  water_surface: {height_m: 51.2}");
  ExpectError("dataset.yaml", 26, "sensors.water_surface.sigma_m");
}

TEST_F(SensorDatasetTest, UnknownMap) {
  ReplaceLine("dataset.yaml", 33, "  chart: {file: ortho.tif}");
  ExpectError("dataset.yaml", 33, "maps.chart");
}

}  // namespace
}  // namespace skerry
