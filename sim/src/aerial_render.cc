#include "skerry/sim/aerial_render.h"

#include <cpl_conv.h>
#include <ogr_spatialref.h>

#include <GeographicLib/UTMUPS.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <stdexcept>
#include <vector>

#include "random.h"

namespace skerry::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
constexpr double kAmbient = 0.35;  // share of the light that is not the sun's direct beam
constexpr double kWaterAlbedo = 0.09;

// Value noise in [-1, 1]: random values on the integer lattice of (x, y) / scale, hashed from
// the lattice point and `key`, blended by the smooth step 3t^2 - 2t^3 (Perlin 1985's lattice
// noise with values instead of gradients).
double LatticeValue(std::int64_t i, std::int64_t j, std::uint64_t key) {
  const std::uint64_t h =
      SplitMix64(key ^ SplitMix64(static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ULL ^
                                  static_cast<std::uint64_t>(j)));
  return static_cast<double>(h >> 11) * 0x1.0p-52 - 1.0;
}

double ValueNoise(double x, double y, double scale, std::uint64_t key) {
  const double fx = x / scale, fy = y / scale;
  const double x0 = std::floor(fx), y0 = std::floor(fy);
  const auto i = static_cast<std::int64_t>(x0);
  const auto j = static_cast<std::int64_t>(y0);
  auto smooth = [](double t) { return t * t * (3.0 - 2.0 * t); };
  const double tx = smooth(fx - x0), ty = smooth(fy - y0);
  const double a = LatticeValue(i, j, key), b = LatticeValue(i + 1, j, key);
  const double c = LatticeValue(i, j + 1, key), d = LatticeValue(i + 1, j + 1, key);
  return (a + (b - a) * tx) * (1.0 - ty) + (c + (d - c) * tx) * ty;
}

// Texture factor around 1 for a surface point, in the surface's own coordinates: (east, north)
// on a top, (along the wall, up) on a wall.
double Texture(const Eigen::Vector3d& p, const Eigen::Vector3d& n, std::uint64_t key) {
  double s, t;
  if (std::abs(n.z()) > 0.5) {
    s = p.x();
    t = p.y();
  } else {
    s = -n.y() * p.x() + n.x() * p.y();
    t = p.z();
  }
  return 1.0 + 0.06 * ValueNoise(s, t, 0.4, key) + 0.08 * ValueNoise(s, t, 3.0, key + 1) +
         0.05 * ValueNoise(s, t, 15.0, key + 2);
}

// The water's brightness factor: a swell of crests 3.1 m apart, bent by noise, and small ripples.
double Ripples(const Eigen::Vector3d& p, std::uint64_t key) {
  const double bend = 2.0 * ValueNoise(p.x(), p.y(), 9.0, key + 3);
  const double swell = std::sin(2.0 * kPi * (0.8 * p.x() + 0.6 * p.y()) / 3.1 + bend);
  return 1.0 + 0.15 * swell + 0.12 * ValueNoise(p.x(), p.y(), 1.2, key + 4);
}

struct Utm {
  int zone;
  bool north;
};

Eigen::Vector2d ToUtm(const LocalFrame& frame, const Utm& utm, const Eigen::Vector3d& p_w) {
  const Eigen::Vector3d llh = frame.ToGeodetic(p_w);
  int zone = 0;
  bool north = true;
  double x = 0.0, y = 0.0, gamma = 0.0, k = 0.0;
  GeographicLib::UTMUPS::Forward(llh.x(), llh.y(), zone, north, x, y, gamma, k, utm.zone);
  if (north != utm.north) {  // across the equator: keep the hemisphere's false northing
    y += north ? GeographicLib::UTMUPS::UTMShift() : -GeographicLib::UTMUPS::UTMShift();
  }
  return Eigen::Vector2d(x, y);
}

Eigen::Vector2d FromUtm(const LocalFrame& frame,
                        const Utm& utm,
                        const Eigen::Vector2d& en,
                        double height_m) {
  double lat = 0.0, lon = 0.0;
  GeographicLib::UTMUPS::Reverse(utm.zone, utm.north, en.x(), en.y(), lat, lon);
  return frame.ToEnu(lat, lon, height_m).head<2>();
}

std::string UtmWkt(const Utm& utm) {
  OGRSpatialReference srs;
  const int epsg = (utm.north ? 32600 : 32700) + utm.zone;  // WGS 84 / UTM zone N / S
  if (srs.importFromEPSG(epsg) != OGRERR_NONE) {
    throw std::runtime_error("GDAL cannot make the CRS EPSG:" + std::to_string(epsg));
  }
  char* text = nullptr;
  srs.exportToWkt(&text);
  std::string wkt = text != nullptr ? text : "";
  CPLFree(text);
  return wkt;
}

}  // namespace

Eigen::Vector2d AerialPhoto::EnuToPixel(const Eigen::Vector2d& p_w) const {
  return pixel_to_enu.leftCols<2>().inverse() * (p_w - pixel_to_enu.col(2));
}

AerialPhoto RenderAerialPhoto(const HarbourWorld& world,
                              const GeoOrigin& origin,
                              const AerialImageSim& options,
                              const Eigen::AlignedBox2d& extent_w,
                              const Eigen::Vector2d& nadir_w,
                              std::uint64_t seed,
                              const std::function<void(double)>& progress) {
  if (!(options.resolution_m > 0.0) || !(options.camera_height_m > 0.0)) {
    throw std::invalid_argument("RenderAerialPhoto: resolution and height must be > 0");
  }
  const LocalFrame frame(origin);
  const double water = world.water_level_m();
  const int zone = GeographicLib::UTMUPS::StandardZone(origin.lat_deg, origin.lon_deg);
  if (zone == GeographicLib::UTMUPS::UPS) {
    throw std::invalid_argument("RenderAerialPhoto: the origin is beyond the UTM zones");
  }
  const Utm utm{zone, origin.lat_deg >= 0.0};

  // The grid: the extent's UTM bounds (corners and mid-sides), snapped outward to the resolution.
  const double res = options.resolution_m;
  Eigen::AlignedBox2d utm_box;
  for (int i = 0; i <= 2; ++i) {
    for (int j = 0; j <= 2; ++j) {
      const Eigen::Vector2d p =
          extent_w.min() + 0.5 * Eigen::Vector2d(i, j).cwiseProduct(extent_w.sizes());
      utm_box.extend(ToUtm(frame, utm, Eigen::Vector3d(p.x(), p.y(), water)));
    }
  }
  const double e0 = std::floor(utm_box.min().x() / res) * res;
  const double n1 = std::ceil(utm_box.max().y() / res) * res;
  const int width = static_cast<int>(std::ceil((utm_box.max().x() - e0) / res - 1e-9));
  const int height = static_cast<int>(std::ceil((n1 - utm_box.min().y()) / res - 1e-9));
  if (width < 1 || height < 1 || static_cast<double>(width) * height > 4e8) {
    throw std::invalid_argument("RenderAerialPhoto: the image would have " + std::to_string(width) +
                                " x " + std::to_string(height) + " pixels");
  }
  AerialPhoto photo;
  photo.resolution_m = res;
  photo.utm_zone = utm.zone;
  photo.north = utm.north;
  photo.top_left_east_m = e0 + 0.5 * res;
  photo.top_left_north_m = n1 - 0.5 * res;

  // Pixel -> ENU: exact at a 5 x 5 lattice, fitted affinely (UTM is conformal and the tangent
  // plane curves away by x^2 / 2R: over a harbour the map is affine to well below a millimetre).
  const double h_water = origin.height_m + water;
  Eigen::MatrixXd A(25, 3);
  Eigen::MatrixXd b(25, 2);
  for (int k = 0; k < 25; ++k) {
    const double u = (width - 1) * (k % 5) / 4.0;
    const double v = (height - 1) * (k / 5) / 4.0;
    A.row(k) << u, v, 1.0;
    b.row(k) = FromUtm(frame, utm,
                       {photo.top_left_east_m + u * res, photo.top_left_north_m - v * res}, h_water)
                   .transpose();
  }
  const Eigen::Matrix<double, 3, 2> M = A.colPivHouseholderQr().solve(b);
  photo.pixel_to_enu = M.transpose();
  const double fit_error = (A * M - b).rowwise().norm().maxCoeff();
  if (fit_error > 0.005) {
    throw std::invalid_argument("RenderAerialPhoto: the extent is too large for one affine map (" +
                                std::to_string(fit_error) + " m off)");
  }

  // Render: for each pixel, the ray from the camera to its grid point on the terrain.
  const Eigen::Vector2d offset(options.image_offset_east_m, options.image_offset_north_m);
  photo.camera_w = Eigen::Vector3d(nadir_w.x(), nadir_w.y(), water + options.camera_height_m);
  const Eigen::Vector3d& C = photo.camera_w;
  const double az = options.sun_azimuth_deg * kDeg, el = options.sun_elevation_deg * kDeg;
  const Eigen::Vector3d sun(std::sin(az) * std::cos(el), std::cos(az) * std::cos(el), std::sin(el));
  const double lit_top = kAmbient + (1.0 - kAmbient) * sun.z();
  const std::uint64_t texture_key = SplitMix64(seed ^ 0x5eed5eedULL);
  Rng noise(seed, RngStream::kAerialImage);
  photo.grey.create(height, width, CV_8UC1);
  const Eigen::Matrix<double, 2, 3>& P = photo.pixel_to_enu;
  for (int v = 0; v < height; ++v) {
    if (progress && v % 64 == 0) progress(static_cast<double>(v) / height);
    std::uint8_t* row = photo.grey.ptr<std::uint8_t>(v);
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector2d g = P * Eigen::Vector3d(u, v, 1.0) - offset;
      const Eigen::Vector3d target(g.x(), g.y(), world.TerrainHeight(g, WorldView::kImage));
      const Eigen::Vector3d ray = target - C;
      const double length = ray.norm();
      const std::optional<RayHit> hit = world.Raycast(C, ray, length + 1.0, WorldView::kImage);
      Eigen::Vector3d point, normal = Eigen::Vector3d::UnitZ();
      double albedo;
      if (hit) {
        point = hit->point_w;
        normal = hit->normal_w;
        albedo = world.boxes()[hit->box].albedo *
                 Texture(point, normal, texture_key + 16 * static_cast<std::uint64_t>(hit->box));
      } else {  // the water
        point = C + ray * ((water - C.z()) / ray.z());
        albedo = kWaterAlbedo * Ripples(point, texture_key);
      }
      const double facing = normal.dot(sun);
      double light = kAmbient;
      if (facing > 0.0 &&
          !world.Raycast(point + 0.01 * normal, sun, 1000.0, WorldView::kImage).has_value()) {
        light += (1.0 - kAmbient) * facing;
      }
      const double grey = 255.0 * albedo * light / lit_top + options.noise_grey * noise.Normal();
      row[u] = static_cast<std::uint8_t>(std::clamp(std::lround(grey), 0L, 255L));
    }
  }
  if (progress) progress(1.0);
  return photo;
}

void WriteAerialPhoto(const AerialPhoto& photo, const std::string& png_path) {
  namespace fs = std::filesystem;
  if (!cv::imwrite(png_path, photo.grey)) throw std::runtime_error("cannot write " + png_path);
  const fs::path stem = fs::path(png_path).parent_path() / fs::path(png_path).stem();
  // World file (ESRI): pixel size east, two rotation terms, pixel size north (negative), then
  // the map coordinates of the centre of the top-left pixel.
  {
    std::ofstream out(stem.string() + ".pgw");
    char line[256];
    std::snprintf(line, sizeof(line), "%.6f\n0\n0\n%.6f\n%.6f\n%.6f\n", photo.resolution_m,
                  -photo.resolution_m, photo.top_left_east_m, photo.top_left_north_m);
    out << line;
    if (!out) throw std::runtime_error("cannot write " + stem.string() + ".pgw");
  }
  {
    std::ofstream out(stem.string() + ".prj");
    out << UtmWkt({photo.utm_zone, photo.north}) << '\n';
    if (!out) throw std::runtime_error("cannot write " + stem.string() + ".prj");
  }
}

void RenderAerialImage(const ScenarioConfig& config,
                       std::uint64_t seed,
                       Dataset* data,
                       const std::string& out_dir,
                       const std::function<void(double)>& progress) {
  const HarbourSpec& spec = config.harbour;
  if (!spec.enabled || !spec.aerial_image.enabled) return;
  const HarbourWorld world = BuildHarbour(spec, seed);
  Eigen::AlignedBox2d extent = world.bounds();
  for (const NavState& s : data->truth_states) extent.extend(s.p_w_b.head<2>());
  const Eigen::Vector2d margin = Eigen::Vector2d::Constant(spec.aerial_image.margin_m);
  extent = Eigen::AlignedBox2d(extent.min() - margin, extent.max() + margin);
  const AerialPhoto photo =
      RenderAerialPhoto(world, config.origin, spec.aerial_image, extent,
                        {spec.centre_east_m, spec.centre_north_m}, seed, progress);
  std::filesystem::create_directories(out_dir);
  const std::string path = (std::filesystem::absolute(out_dir) / "orthophoto.png").string();
  WriteAerialPhoto(photo, path);
  // The photograph's projection centre, as an aerial survey states it with its images.
  const Eigen::Vector3d llh = LocalFrame(config.origin).ToGeodetic(photo.camera_w);
  data->orthophoto = MapConfig{path, "", "", GeoOrigin{llh.x(), llh.y(), llh.z()}, std::nullopt};
}

}  // namespace skerry::sim
