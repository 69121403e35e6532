// Prior work's baseline (baseline_grid_search.h), component by component.

#include <gtest/gtest.h>

#include <cmath>

#include "skerry/skyline/baseline_grid_search.h"

namespace skerry::skyline::baseline {
namespace {

std::vector<double> Flat(int n, double row) { return std::vector<double>(n, row); }

// A triangular bump of the given height and base width centred at c.
void Bump(std::vector<double>* rows, int c, double height, double width) {
  for (int u = 0; u < static_cast<int>(rows->size()); ++u) {
    const double t = 1.0 - std::abs(u - c) / (0.5 * width);
    if (t > 0) (*rows)[u] -= std::round(height * t);
  }
}

TEST(Baseline, HilltopsAbove5PxHighAnd25PxWide) {
  std::vector<double> rows = Flat(400, 300);
  Bump(&rows, 60, 6, 30);    // a hilltop
  Bump(&rows, 160, 4, 40);   // too low
  Bump(&rows, 260, 12, 20);  // too narrow
  Bump(&rows, 340, 20, 60);  // a hilltop
  const std::vector<int> h = Hilltops(rows, 5.0, 25.0);
  ASSERT_EQ(h.size(), 2u);
  EXPECT_EQ(h[0], 60);
  EXPECT_EQ(h[1], 340);
}

TEST(Baseline, SadRecoversAShiftAndAVerticalOffset) {
  std::vector<double> expected = Flat(800, 300), observed = Flat(800, 290);
  Bump(&expected, 300, 30, 80);
  Bump(&expected, 360, 15, 50);
  Bump(&observed, 337, 30, 80);
  Bump(&observed, 397, 15, 50);
  double mean_abs = 0;
  EXPECT_EQ(SadShift(expected, observed, 300, 40, 150, &mean_abs), 37);
  EXPECT_LT(mean_abs, 0.5);
}

TEST(Baseline, BadInputIsAFailedResultNotACrash) {
  geo::EnuHeightGrid grid;
  grid.cols = grid.rows = 3;
  grid.spacing_m = 100;
  grid.up_m.assign(9, 0.0);
  const CameraModel camera(PinholeFromFov("camera", 640, 480, 70.0));
  BaselineInput in;
  EXPECT_FALSE(LocateFrameBaseline(grid, camera, cv::Mat(), in).ok);
  EXPECT_FALSE(LocateFrameBaseline(grid, camera, cv::Mat(480, 640, CV_8UC1, cv::Scalar(0)), in).ok);
}

}  // namespace
}  // namespace skerry::skyline::baseline
