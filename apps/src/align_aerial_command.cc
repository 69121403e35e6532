#include "align_aerial_command.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "finite_number.h"
#include "output_folder.h"
#include "run_outputs.h"
#include "skerry/core/earth_model.h"
#include "skerry/core/geodesy.h"
#include "skerry/core/heading.h"
#include "skerry/core/input_error.h"
#include "skerry/geo/orthophoto.h"
#include "skerry/geo/point_cloud.h"
#include "skerry/lidar_aerial/scan_preparation.h"
#include "skerry/lidar_aerial/scan_registration.h"

namespace skerry::cli {

namespace {

constexpr double kDeg = M_PI / 180.0;

struct AlignAerialOptions {
  std::string cloud;
  std::string image;
  std::string out;
  std::string cloud_crs;
  std::string image_crs;
  std::string vertical_datum = "egm96";
  std::string start;  // "LAT,LON,HEADING_DEG": a cloud in its sensor's frame
  double search_radius_m = 30.0;
  double heading_range_deg = 20.0;
  int jackknife_groups_per_axis = 4;
  bool overwrite = false;
};

const std::vector<std::string>& AlignFiles() {
  static const std::vector<std::string> files = {"alignment.json", "alignment.png"};
  return files;
}

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// People read headings clockwise from north; the planar pose's yaw is counter-clockwise from the
// frame's east. North is the local meridian's at the aligned position: the frame's is the
// image's centre's, and a county's mosaic reaches kilometres from it (HeadingDegAt).
double HeadingDeg(const LocalFrame& frame, const lidar_aerial::PlanarPose& pose) {
  return HeadingDegAt(EarthModel(frame.origin()), Eigen::Vector3d(pose.t.x(), pose.t.y(), 0.0),
                      Eigen::Quaterniond(Eigen::AngleAxisd(pose.yaw, Eigen::Vector3d::UnitZ())));
}

int AlignAerial(const AlignAerialOptions& o) {
  PrepareOutputFolder(o.out, AlignFiles(), o.overwrite);
  // The ENU frame at the image's centre (a first load finds it). The pixels stay in the file and
  // the map reads the window under it: a county's mosaic or a drone's costs the memory of the
  // cloud's surroundings.
  geo::OrthophotoOptions image_options;
  image_options.crs = o.image_crs;
  image_options.crs_given_as = "--image-crs";
  image_options.on_disk = true;
  const geo::Orthophoto rough(o.image, LocalFrame({0.0, 0.0, 0.0}), image_options);
  const Eigen::Vector3d centre = rough.frame().ToGeodetic(
      rough.PixelToEnu(0.5 * (rough.width() - 1), 0.5 * (rough.height() - 1), 0.0));
  const LocalFrame frame({centre.x(), centre.y(), 0.0});
  const geo::Orthophoto ortho(o.image, frame, image_options);

  // The scan: a georeferenced cloud centred on its middle, starting where the files put it; or
  // a cloud in its sensor's frame at --start.
  const auto t_load = std::chrono::steady_clock::now();
  const geo::PointCloud cloud = geo::LoadPointCloud(o.cloud);
  std::vector<Eigen::Vector3d> scan;
  lidar_aerial::PlanarPose start;
  std::string start_from;
  if (o.start.empty()) {
    if (cloud.frame != geo::CloudFrame::kCrs && o.cloud_crs.empty()) {
      throw InputError(o.cloud, 0, "start",
                       "the cloud is in its sensor's frame: give --start LAT,LON,HEADING_DEG");
    }
    geo::CloudToEnuOptions to_enu(o.vertical_datum == "egm96" ? geo::VerticalDatum::kEgm96
                                                              : geo::VerticalDatum::kEllipsoidal);
    to_enu.crs = o.cloud_crs;
    geo::PointCloud enu = cloud;
    enu.frame = geo::CloudFrame::kCrs;
    enu = geo::PointCloudToEnu(enu, frame, to_enu);
    Eigen::AlignedBox2d box;
    for (const Eigen::Vector3d& p : enu.points) box.extend(p.head<2>().eval());
    start = {box.center(), 0.0};
    for (const Eigen::Vector3d& p : enu.points) {
      scan.push_back(p - Eigen::Vector3d(start.t.x(), start.t.y(), 0.0));
    }
    start_from = "the cloud's CRS";
  } else {
    if (cloud.frame == geo::CloudFrame::kCrs) {
      throw InputError(o.cloud, 0, "start",
                       "the cloud is georeferenced (" + cloud.crs_note +
                           "): it starts where its file puts it; leave out --start");
    }
    double lat = 0.0, lon = 0.0, heading = 0.0;
    char c1 = 0, c2 = 0;
    std::istringstream in(o.start);
    const bool parsed = static_cast<bool>(in >> lat >> c1 >> lon >> c2 >> heading) &&
                        (in >> std::ws).peek() == std::char_traits<char>::eof();
    if (!parsed || c1 != ',' || c2 != ',' || !std::isfinite(lat) || !std::isfinite(lon) ||
        !std::isfinite(heading) || std::abs(lat) > 90.0 || std::abs(lon) > 180.0) {
      throw InputError("--start", 0, "start",
                       "expected LAT,LON,HEADING_DEG, got '" + o.start + "'");
    }
    const Eigen::Vector3d p = frame.ToEnu(lat, lon, 0.0);
    start = {p.head<2>(), (90.0 - heading) * kDeg};
    scan = cloud.points;
    start_from = "--start";
  }
  const double load_s = Seconds(t_load);
  if (scan.empty()) throw InputError(o.cloud, 0, "points", "the cloud holds no points");

  const auto t_prep = std::chrono::steady_clock::now();
  lidar_aerial::PreparedScan prepared;
  try {
    prepared = lidar_aerial::PrepareScan(scan, cloud.intensity, Eigen::Quaterniond::Identity());
  } catch (const std::invalid_argument& e) {
    throw InputError(o.cloud, 0, "points", e.what());
  }
  const double prep_s = Seconds(t_prep);
  if (prepared.points_s.size() < 10) {
    throw InputError(o.cloud, 0, "points",
                     "only " + std::to_string(prepared.points_s.size()) +
                         " edge points (walls, low rims, ground-level intensity edges) in " +
                         std::to_string(scan.size()) + " returns: nothing an aerial image shows");
  }

  // The map over the scan's reach around the start, plus the search.
  double reach = 0.0;
  for (const Eigen::Vector3d& p : prepared.points_s) reach = std::max(reach, p.head<2>().norm());
  const double margin = reach + o.search_radius_m + 10.0;
  const Eigen::AlignedBox2d map_box(start.t - Eigen::Vector2d::Constant(margin),
                                    start.t + Eigen::Vector2d::Constant(margin));
  const auto t_map = std::chrono::steady_clock::now();
  std::optional<lidar_aerial::AerialMap> made;
  try {
    made.emplace(ortho, map_box);
  } catch (const InputError& e) {
    if (e.field() != "coverage") throw;  // a box off the image: no edge point on it, below
  }
  const double map_s = Seconds(t_map);

  // The image must lie under the scan at the start: half its edge points at least on cells that
  // hold data (the map's, read from the image's pixels; a pixel at a time from a JPEG would decode
  // the image from its top each time).
  int covered = 0;
  for (const Eigen::Vector3d& p : prepared.points_s) {
    covered += made && made->Covers(start.Apply(p.head<2>()));
  }
  if (covered < 0.5 * static_cast<double>(prepared.points_s.size())) {
    throw InputError(o.cloud, 0, "coverage",
                     std::to_string(covered) + " of " + std::to_string(prepared.points_s.size()) +
                         " edge points at the start (" + start_from +
                         ") lie over pixels of the image " + o.image +
                         " that hold data: the image does not cover the cloud");
  }
  const lidar_aerial::AerialMap& map = *made;
  const auto field = std::make_shared<lidar_aerial::EdgeDistanceField>(map);
  lidar_aerial::RegistrationOptions ro;
  ro.coarse.search_radius_m = o.search_radius_m;
  ro.coarse.heading_range_deg = o.heading_range_deg;
  ro.jackknife_groups_per_axis = o.jackknife_groups_per_axis;
  const auto t_reg = std::chrono::steady_clock::now();
  const lidar_aerial::Registration r =
      lidar_aerial::RegisterScan(map, field, prepared.points_s, start, ro);
  const double reg_s = Seconds(t_reg);
  if (!r.valid) {
    throw InputError(
        o.cloud, 0, "alignment",
        "no alignment found within " + std::to_string(o.search_radius_m) + " m of " + start_from);
  }

  const Eigen::Vector3d llh = frame.ToGeodetic(Eigen::Vector3d(r.pose.t.x(), r.pose.t.y(), 0.0));
  const Eigen::Vector2d shift = r.pose.t - start.t;
  const double turn_deg = lidar_aerial::WrapAngle(r.pose.yaw - start.yaw) / kDeg;
  nlohmann::json j;
  j["command"] = "align-aerial";
  j["cloud"] = {{"path", o.cloud},
                {"returns", scan.size()},
                {"edge_points", prepared.points_s.size()},
                {"wall_columns", prepared.wall_columns},
                {"rim_columns", prepared.rim_columns},
                {"intensity_columns", prepared.intensity_columns},
                {"dropped_high", prepared.dropped_high}};
  j["image"] = {{"path", o.image},
                {"crs_source", ortho.crs_source()},
                {"width", ortho.width()},
                {"height", ortho.height()},
                {"gsd_m", ortho.ground_sample_distance_m()},
                {"value_range", {ortho.value_range().x(), ortho.value_range().y()}}};
  j["map"] = {{"cols", map.cols()},
              {"rows", map.rows()},
              {"resolution_m", map.resolution_m()},
              {"valid_share", static_cast<double>(cv::countNonZero(map.valid())) /
                                  static_cast<double>(map.valid().total())}};
  j["start_from"] = start_from;
  j["alignment"] = {{"latitude_deg", llh.x()},
                    {"longitude_deg", llh.y()},
                    {"heading_deg", HeadingDeg(frame, r.pose)},
                    {"shift_east_m", shift.x()},
                    {"shift_north_m", shift.y()},
                    {"turn_clockwise_deg", -turn_deg},
                    {"sd_east_m", std::sqrt(r.covariance(0, 0))},
                    {"sd_north_m", std::sqrt(r.covariance(1, 1))},
                    {"sd_heading_deg", std::sqrt(r.covariance(2, 2)) / kDeg},
                    {"curvature_sd_east_m", std::sqrt(r.curvature_covariance(0, 0))},
                    {"curvature_sd_north_m", std::sqrt(r.curvature_covariance(1, 1))},
                    {"curvature_sd_heading_deg", std::sqrt(r.curvature_covariance(2, 2)) / kDeg},
                    {"constraint_ratio", r.constraint_ratio},
                    {"weak_direction_en", {r.weak_direction.x(), r.weak_direction.y()}},
                    {"rms_distance_m", r.rms_distance_m},
                    {"inlier_share", r.inlier_share},
                    {"iterations", r.iterations}};
  if (r.jackknife) {
    const lidar_aerial::SpatialJackknife& jk = *r.jackknife;
    j["jackknife"] = {{"groups", jk.groups},
                      {"sd_east_m", std::sqrt(jk.covariance(0, 0))},
                      {"sd_north_m", std::sqrt(jk.covariance(1, 1))},
                      {"sd_heading_deg", std::sqrt(jk.covariance(2, 2)) / kDeg},
                      {"max_shift_m", jk.max_shift_m},
                      {"max_turn_deg", jk.max_turn_rad / kDeg}};
  } else {
    j["jackknife"] = nullptr;
  }
  j["coarse_search"] = {{"score", r.coarse.score},
                        {"ambiguity", r.coarse.ambiguity},
                        {"ambiguous", r.coarse.ambiguous},
                        {"headings", r.coarse.headings},
                        {"search_radius_m", o.search_radius_m},
                        {"heading_range_deg", o.heading_range_deg}};
  j["timing_s"] = {{"load", load_s}, {"prepare", prep_s}, {"map", map_s}, {"register", reg_s}};

  // The figure: the map, its edges (red), the edge points at the start (green) and aligned (blue).
  cv::Mat img;
  cv::cvtColor(map.grey(), img, cv::COLOR_GRAY2BGR);
  img.setTo(cv::Scalar(0, 0, 255), map.edges());
  for (const auto& [pose, colour] :
       {std::pair(start, cv::Scalar(0, 255, 0)), std::pair(r.pose, cv::Scalar(255, 0, 0))}) {
    for (const Eigen::Vector3d& p : prepared.points_s) {
      const Eigen::Vector2d g = map.ToGrid(pose.Apply(p.head<2>()));
      cv::circle(img, cv::Point(static_cast<int>(g.x()), static_cast<int>(g.y())), 1, colour,
                 cv::FILLED);
    }
  }
  cv::imwrite(o.out + "/alignment.png", img);
  WriteJson(o.out + "/alignment.json", j);

  char curvature[96];
  std::snprintf(curvature, sizeof curvature, "the curvature alone: %.2f m, %.2f m, %.2f deg",
                std::sqrt(r.curvature_covariance(0, 0)), std::sqrt(r.curvature_covariance(1, 1)),
                std::sqrt(r.curvature_covariance(2, 2)) / kDeg);
  const std::string sd_from = r.jackknife ? "spatial jackknife over " +
                                                std::to_string(r.jackknife->groups) + " blocks; " +
                                                curvature
                                          : std::string(curvature);
  std::printf(
      "skerry align-aerial: %zu returns, %zu edge points; aligned %.2f m east, %.2f m north and "
      "%.2f deg clockwise from %s (sd %.2f m, %.2f m, %.2f deg; %s); heading %.2f deg\n"
      "  coarse search: score %.3f, ambiguity %.2f%s; position constraint ratio %.2f%s\n"
      "results in %s (alignment.json, alignment.png)\n",
      scan.size(), prepared.points_s.size(), shift.x(), shift.y(), -turn_deg, start_from.c_str(),
      std::sqrt(r.covariance(0, 0)), std::sqrt(r.covariance(1, 1)),
      std::sqrt(r.covariance(2, 2)) / kDeg, sd_from.c_str(), HeadingDeg(frame, r.pose),
      r.coarse.score, r.coarse.ambiguity, r.coarse.ambiguous ? " (AMBIGUOUS)" : "",
      r.constraint_ratio, r.constraint_ratio < 0.05 ? " (weak along one direction)" : "",
      o.out.c_str());
  return 0;
}

}  // namespace

Subcommand AddAlignAerialCommand(CLI::App& app) {
  auto options = std::make_shared<AlignAerialOptions>();
  Subcommand s;
  s.app = app.add_subcommand("align-aerial",
                             "Register a LiDAR cloud to a georeferenced aerial image by their "
                             "edges (docs/lidar_aerial.md)");
  s.app->add_option("--cloud", options->cloud, "Point cloud (.las, .pcd, .ply, KITTI .bin)")
      ->required();
  s.app->add_option("--image", options->image, "Orthophoto (GeoTIFF, or JPEG/PNG + world file)")
      ->required();
  s.app->add_option("--out", options->out, "Output folder (alignment.json, alignment.png)")
      ->required();
  s.app->add_option("--cloud-crs", options->cloud_crs,
                    "CRS of the cloud when its file has none (EPSG:..., WKT, .prj)");
  s.app->add_option("--image-crs", options->image_crs,
                    "CRS of the image when it has none (EPSG:..., WKT, .prj)");
  s.app
      ->add_option("--vertical-datum", options->vertical_datum,
                   "Datum of a georeferenced cloud's heights")
      ->check(CLI::IsMember({"egm96", "ellipsoidal"}))
      ->capture_default_str();
  s.app->add_option("--start", options->start,
                    "LAT,LON,HEADING_DEG of a cloud in its sensor's frame (levelled; heading "
                    "clockwise from north)");
  s.app->add_option("--search-radius", options->search_radius_m, "Coarse search half-width, m")
      ->capture_default_str()
      ->check(FiniteNumber(0.0, std::numeric_limits<double>::infinity(), true));
  s.app->add_option("--heading-range", options->heading_range_deg, "Heading sweep +-, degrees")
      ->capture_default_str()
      ->check(FiniteNumber(0.0, 180.0));
  s.app
      ->add_option("--jackknife", options->jackknife_groups_per_axis,
                   "State the sd as at least the spread of a spatial jackknife over N x N blocks "
                   "of the edge points (0: the cost's curvature alone)")
      ->capture_default_str()
      ->check(CLI::IsMember({0, 2, 3, 4, 5, 6, 7, 8}));
  s.app->add_flag("--overwrite", options->overwrite, "Replace results already in --out");
  s.run = [options]() { return AlignAerial(*options); };
  return s;
}

}  // namespace skerry::cli
