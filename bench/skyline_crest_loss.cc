/// \file
/// How far a DEM's crests sit below the terrain's, measured on real terrain, and how much of it
/// the map's sharpening (geo/terrain_sharpening.h) gives back.
///
/// The terrain: the Engabreen glacier's 3 m lidar DEM (../shared/data/engabreen), resampled onto
/// an ENU grid at 3 m. The raster a user would have: block means of that grid over C x C metres
/// (C = 30 m: SRTM1 / Copernicus GLO-30; 90 m: SRTM3), each a mean over its footprint as a real
/// raster's height is. The map: that raster resampled at the estimator's spacing (C / oversampling,
/// bilinear, as skyline::HorizonForTrack does), plain or sharpened. From viewpoints spread over
/// the DEM (a node every --step metres, --clearance above the higher of terrain and map), the
/// horizon is traced over 360 azimuths on the terrain and on each map; an azimuth counts when
/// both horizons lie on the map (not truncated) at least 3 C away. Per map: the elevation error
/// dE = E_map - E_terrain (mrad), and dE d (m, d the terrain horizon's distance), the crest's
/// height deficit, which a ridge 30 km off turns into dE = deficit / 30 km.
///
/// With --noise S each raster node gains white noise of S metres (a fixed seed): a radar DEM's
/// speckle (SRTM: a few metres), which sharpening amplifies and a horizon, a maximum, picks up.
///
/// Usage: skerry_skyline_crest_loss [SHARED_DATA_DIR] [--step M] [--clearance M] [--noise S]

#include <GeographicLib/UTMUPS.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "skerry/geo/dem.h"
#include "skerry/geo/terrain_sharpening.h"
#include "skerry/sim/terrain_relief.h"
#include "skerry/skyline/horizon_predictor.h"

using namespace skerry;

namespace {

constexpr double kEarthRadiusM = 6371000.0;

/// `raster` resampled bilinearly at `spacing`, nodes from its first node plus `offset`.
geo::EnuHeightGrid Resample(const geo::EnuHeightGrid& raster, double spacing, double offset) {
  return geo::Resampled(raster, raster.origin_w + Eigen::Vector2d::Constant(offset), spacing,
                        static_cast<int>((raster.cols - 1) * raster.spacing_m / spacing),
                        static_cast<int>((raster.rows - 1) * raster.spacing_m / spacing));
}

struct Stats {
  std::vector<double> de_mrad, deficit_m;
};

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * (v.size() - 1) + 0.5)];
}

double Mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? NAN : s / v.size();
}

}  // namespace

int main(int argc, char** argv) {
  std::string shared = "../shared/data";
  double step_m = 150.0, clearance_m = 5.0, noise_m = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help") {
      std::printf(
          "usage: skerry_skyline_crest_loss [SHARED_DATA_DIR] [--step M] [--clearance M] "
          "[--noise S]\n");
      return 0;
    } else if (a == "--step" && i + 1 < argc) {
      step_m = std::atof(argv[++i]);
    } else if (a == "--noise" && i + 1 < argc) {
      noise_m = std::atof(argv[++i]);
    } else if (a == "--clearance" && i + 1 < argc) {
      clearance_m = std::atof(argv[++i]);
    } else {
      shared = a;
    }
  }
  const std::string path = shared + "/engabreen/engabreen_dem_3m_utm33n.asc";
  if (!std::filesystem::exists(path)) {
    std::fprintf(stderr, "skerry_skyline_crest_loss: %s missing\n", path.c_str());
    return 2;
  }
  double lat, lon;
  GeographicLib::UTMUPS::Reverse(33, true, 446722.0, 7396671.0, lat, lon);
  geo::DemOptions options(geo::VerticalDatum::kEllipsoidal);
  options.crs = "EPSG:32633";
  const geo::Dem dem(path, LocalFrame({lat, lon, 0.0}), options);
  const geo::EnuHeightGrid terrain = dem.ResampleToEnu(dem.footprint_enu(), 3.0);
  skyline::HorizonOptions ho;
  ho.max_range_m = 5000.0;

  struct Map {
    std::string name;
    size_t truth;  ///< index into truths: the terrain traced with this map's min range
    skyline::HorizonPredictor predictor;
    Stats stats;
  };
  std::vector<skyline::HorizonPredictor> truths;
  std::vector<Map> maps;
  for (int b : {10, 30}) {
    geo::EnuHeightGrid raster = geo::BlockMeans(terrain, b);
    if (noise_m > 0) {
      std::mt19937_64 rng(b);
      std::normal_distribution<double> normal(0.0, noise_m);
      for (double& z : raster.up_m) z += normal(rng);
    }
    const double cell = raster.spacing_m;
    skyline::HorizonOptions mo = ho;
    mo.min_range_m = 3.0 * cell;
    truths.emplace_back(terrain, mo);
    char name[96];
    std::snprintf(name, sizeof name, "%.0f m raster itself (its nodes)", cell);
    maps.push_back({name, truths.size() - 1, skyline::HorizonPredictor(raster, mo), {}});
    for (int over : {1, 2}) {
      // Map nodes off the raster's by a third of a node: where they fall is the box's business.
      const geo::EnuHeightGrid plain = Resample(raster, cell / over, cell / over / 3.0);
      std::snprintf(name, sizeof name, "%.0f m raster, map at 1/%d cell", cell, over);
      maps.push_back({name, truths.size() - 1, skyline::HorizonPredictor(plain, mo), {}});
      if (over == 1) continue;
      // The simulator's world from this raster (sim/terrain_relief.h): how high it stands
      // against the real terrain.
      for (double gain : {1.0, 2.0}) {
        for (double sigma : {0.5, 0.75}) {
          geo::EnuHeightGrid world = plain;
          sim::AddTerrainRelief({gain, sigma}, cell, kEarthRadiusM, &world);
          std::snprintf(name, sizeof name, "  the simulator's world, relief %.0f, footprint %.2f",
                        gain, sigma);
          maps.push_back({name, truths.size() - 1, skyline::HorizonPredictor(world, mo), {}});
        }
      }
      for (double gain : {1.0, 2.0, 3.0}) {
        for (double sigma : {0.5, 0.75, 1.0}) {
          geo::EnuHeightGrid sharp = plain;
          geo::SharpenTerrain({gain, sigma * cell}, kEarthRadiusM, &sharp);
          std::snprintf(name, sizeof name, "  sharpened: gain %.0f, footprint sigma %.2f cell",
                        gain, sigma);
          maps.push_back({name, truths.size() - 1, skyline::HorizonPredictor(sharp, mo), {}});
        }
      }
    }
  }

  int viewpoints = 0;
  const int stride = std::max(1, static_cast<int>(step_m / terrain.spacing_m));
  for (int row = stride; row < terrain.rows - stride; row += stride) {
    for (int col = stride; col < terrain.cols - stride; col += stride) {
      const Eigen::Vector2d xy = terrain.NodePosition(col, row);
      double z = terrain.at(col, row);
      bool ok = std::isfinite(z);
      for (const Map& m : maps) {
        double zm;
        ok = ok && m.predictor.Terrain(xy.x(), xy.y(), &zm);
        if (ok) z = std::max(z, zm);
      }
      if (!ok) continue;
      ++viewpoints;
      const Eigen::Vector3d p(xy.x(), xy.y(), z + clearance_m);
      for (int k = 0; k < 360; ++k) {
        const double az = k * M_PI / 180.0;
        std::vector<skyline::HorizonSample> truth;
        for (const auto& t : truths) truth.push_back(t.Trace(p, az, ho.refraction_k, false));
        for (Map& m : maps) {
          const skyline::HorizonSample& t = truth[m.truth];
          if (!t.valid || t.truncated) continue;
          const skyline::HorizonSample h = m.predictor.Trace(p, az, ho.refraction_k, false);
          if (!h.valid || h.truncated) continue;
          const double de = h.elevation_rad - t.elevation_rad;
          m.stats.de_mrad.push_back(1e3 * de);
          m.stats.deficit_m.push_back(de * t.distance_m);
        }
      }
    }
  }
  std::printf(
      "terrain: %s at 3 m (%d x %d nodes); rasters its block means, noise %.1f m; %d viewpoints "
      "every %.0f m, %.0f m above the higher of terrain and maps; 360 azimuths each\n",
      path.c_str(), terrain.cols, terrain.rows, noise_m, viewpoints, step_m, clearance_m);
  std::printf("%-48s %8s %22s %30s\n", "map", "azimuths", "dE mrad: mean / median",
              "dE x d m: mean / p10 / p90");
  for (const Map& m : maps) {
    const Stats& s = m.stats;
    std::printf("%-48s %8zu %10.3f / %8.3f %10.2f / %7.2f / %7.2f\n", m.name.c_str(),
                s.de_mrad.size(), Mean(s.de_mrad), Quantile(s.de_mrad, 0.5), Mean(s.deficit_m),
                Quantile(s.deficit_m, 0.1), Quantile(s.deficit_m, 0.9));
  }
  return 0;
}
