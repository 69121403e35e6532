// blocks.csv (`skerry run`): the window's decision about every block of the sensors beyond IMU
// and GNSS beside the frontends' own figures for it, written from a made-up run so that every
// cell can be checked: the columns of two sensors merged, empty cells where a sensor has no such
// column or a block no such figure, a block the frontend has no row for.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "run_outputs.h"

namespace skerry::cli {
namespace {

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

SensorRecord Record(SensorId sensor, TimeNs t, SensorDecision d, int dim, double d2) {
  SensorRecord r;
  r.sensor = sensor;
  r.t_ns = t;
  r.decision = d;
  r.dim = dim;
  r.d2 = d2;
  return r;
}

TEST(BlocksCsv, DecisionsBesideEachFrontendsFiguresPerBlock) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  SensorLog log;
  SensorSpec lidar, camera;
  lidar.name = "lidar";
  camera.name = "camera";
  log.RegisterSensor(lidar);
  log.RegisterSensor(camera);
  log.live_frontend_blocks["lidar"] = [nan] {
    FrontendBlockTable t;
    t.columns = {"edge_points", "constraint_ratio"};
    t.rows[1'000'000'000] = {1200, 0.5};
    t.rows[2'000'000'000] = {40, nan};
    return t;
  };
  log.live_frontend_blocks["camera"] = [] {
    FrontendBlockTable t;
    t.columns = {"samples", "constraint_ratio"};
    t.rows[1'500'000'000] = {240, 0.9};
    return t;
  };
  log.decisions = {Record(0, 1'000'000'000, SensorDecision::kAccepted, 3, 1.25),
                   Record(1, 1'500'000'000, SensorDecision::kRejectedByGate, 240, 400.0),
                   Record(0, 2'000'000'000, SensorDecision::kDropped, 0, 0.0),
                   Record(0, 3'000'000'000, SensorDecision::kAccepted, 3, 2.0)};
  log.decisions.back().reacquired = true;

  const std::string dir = std::string(SKERRY_TEST_TMP_DIR) + "/blocks_csv";
  std::filesystem::create_directories(dir);
  ASSERT_TRUE(WriteBlocksCsv(dir + "/blocks.csv", log));
  EXPECT_EQ(Slurp(dir + "/blocks.csv"),
            "t,sensor,decision,reacquired,dim,d2,edge_points,constraint_ratio,samples\n"
            "1.000000000,lidar,accepted,0,3,1.25,1200,0.5,\n"
            "1.500000000,camera,rejected,0,240,400,,0.9,240\n"
            "2.000000000,lidar,dropped,0,0,0,40,,\n"
            "3.000000000,lidar,accepted,1,3,2,,,\n");

  // A name the user gave with a comma and quotes stays one cell (RFC 4180).
  log.sensors[1].name = "cam,\"port\"";
  log.live_frontend_blocks.clear();
  ASSERT_TRUE(WriteBlocksCsv(dir + "/quoted.csv", log));
  EXPECT_NE(
      Slurp(dir + "/quoted.csv").find("\n1.500000000,\"cam,\"\"port\"\"\",rejected,0,240,400\n"),
      std::string::npos)
      << Slurp(dir + "/quoted.csv");

  // A run without such blocks writes no file.
  std::filesystem::remove(dir + "/none.csv");
  EXPECT_FALSE(WriteBlocksCsv(dir + "/none.csv", SensorLog()));
  EXPECT_FALSE(std::filesystem::exists(dir + "/none.csv"));
}

}  // namespace
}  // namespace skerry::cli
