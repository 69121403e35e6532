#include "skerry/skyline/horizon_predictor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace skerry::skyline {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr double kHalfPi = 1.57079632679489661923;

// The line of an elevation e seen from the camera, linearised in the refraction term: terrain at
// distance s whose slope (z - z_c) / s lies below Below(kappa, s) cannot reach e there (with
// e(s) = atan2(z - z_c, s) + kappa s, tan(e - kappa s) >= tan e - kappa s sec^2 e less a
// second-order term below 1e-6 for kappa s < 1e-3, hence the 1e-5 margin), and needs no atan2.
struct ElevationLine {
  double e = -10.0;
  double tan = -1e300, sec2 = 1.0;  // reaches nothing until set
  void Set(double elevation) {
    e = elevation;
    tan = std::tan(std::max(elevation, -kHalfPi + 1e-6));
    sec2 = 1.0 + tan * tan;
  }
  double Below(double kappa, double s) const { return tan - (kappa * s + 1e-5) * sec2; }
};

/// The end of a golden-section search for the maximum of a function on [a, b]: the interval it
/// narrowed to and the higher of its last two probes.
struct GoldenBracket {
  double a = 0.0, b = 0.0;
  double best = 0.0;
};

/// Golden-section search for the maximum of `f` (unimodal) on [a, b], for `iterations` steps or
/// until the interval is a millimetre wide.
template <typename F>
GoldenBracket GoldenSectionMax(const F& f, double a, double b, int iterations) {
  constexpr double kGolden = 0.6180339887498949;
  double c = b - kGolden * (b - a), d = a + kGolden * (b - a);
  double fc = f(c), fd = f(d);
  for (int it = 0; it < iterations && b - a > 1e-3; ++it) {
    if (fc > fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - kGolden * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + kGolden * (b - a);
      fd = f(d);
    }
  }
  return {a, b, std::max(fc, fd)};
}

}  // namespace

HorizonPredictor::HorizonPredictor(geo::EnuHeightGrid grid, const HorizonOptions& options)
    : grid_(std::move(grid)), options_(options) {
  if (grid_.cols < 2 || grid_.rows < 2 || !(grid_.spacing_m > 0.0) ||
      grid_.up_m.size() != static_cast<size_t>(grid_.cols) * grid_.rows) {
    throw std::invalid_argument(
        "HorizonPredictor: the height grid must be at least 2x2 nodes "
        "with a positive spacing");
  }
  // Level 0: one value per cell (the square between four nodes), the highest of its corners
  // (bilinear interpolation never exceeds it); +inf where a corner is a hole.
  Level base;
  base.cols = grid_.cols - 1;
  base.rows = grid_.rows - 1;
  base.max.resize(static_cast<size_t>(base.cols) * base.rows);
  for (int r = 0; r < base.rows; ++r) {
    for (int c = 0; c < base.cols; ++c) {
      const double a = grid_.at(c, r), b = grid_.at(c + 1, r), d = grid_.at(c, r + 1),
                   e = grid_.at(c + 1, r + 1);
      float m = kInf;
      if (!std::isnan(a) && !std::isnan(b) && !std::isnan(d) && !std::isnan(e)) {
        m = static_cast<float>(std::max(std::max(a, b), std::max(d, e)));
      }
      base.max[static_cast<size_t>(r) * base.cols + c] = m;
    }
  }
  levels_.push_back(std::move(base));
  while (levels_.back().cols > 1 || levels_.back().rows > 1) {
    const Level& below = levels_.back();
    Level up;
    up.cols = (below.cols + 1) / 2;
    up.rows = (below.rows + 1) / 2;
    up.max.assign(static_cast<size_t>(up.cols) * up.rows, -kInf);
    for (int r = 0; r < below.rows; ++r) {
      for (int c = 0; c < below.cols; ++c) {
        float& m = up.max[static_cast<size_t>(r / 2) * up.cols + c / 2];
        m = std::max(m, below.max[static_cast<size_t>(r) * below.cols + c]);
      }
    }
    levels_.push_back(std::move(up));
  }
}

bool HorizonPredictor::Covers(double x, double y) const { return grid_.UpAt(x, y).has_value(); }

void HorizonPredictor::AttachDetail(geo::EnuHeightGrid detail) {
  if (detail.cols != grid_.cols || detail.rows != grid_.rows ||
      detail.spacing_m != grid_.spacing_m || detail.origin_w != grid_.origin_w ||
      detail.up_m.size() != grid_.up_m.size()) {
    throw std::invalid_argument("HorizonPredictor: the detail must have the map's geometry");
  }
  detail_ = std::move(detail);
}

double HorizonPredictor::DetailAt(double x, double y) const {
  if (detail_.up_m.empty()) return 0.0;
  return detail_.UpAt(x, y).value_or(0.0);
}

bool HorizonPredictor::Terrain(double x, double y, double* z) const {
  const auto v = grid_.UpAt(x, y);
  if (!v) return false;
  *z = *v;
  return true;
}

HorizonSample HorizonPredictor::Trace(const Eigen::Vector3d& p_w,
                                      double azimuth_rad,
                                      double refraction_k,
                                      bool derivatives) const {
  HorizonSample out;
  const double dx = std::sin(azimuth_rad), dy = std::cos(azimuth_rad);
  const double sp = grid_.spacing_m;
  const double ox = grid_.origin_w.x(), oy = grid_.origin_w.y();
  const double x_max = ox + sp * (grid_.cols - 1), y_max = oy + sp * (grid_.rows - 1);
  const double kappa = refraction_k / (2.0 * options_.earth_radius_m);
  const double tol = options_.edge_tolerance_rad;
  if (!p_w.allFinite() || !std::isfinite(azimuth_rad) || !std::isfinite(refraction_k)) return out;

  // The stretch of the ray over the grid's rectangle (slab method).
  double s_in = 0.0, s_out = options_.max_range_m;
  const auto slab = [&](double p, double d, double lo, double hi) {
    if (std::abs(d) < 1e-15) {
      if (p < lo || p > hi) s_out = -1.0;
      return;
    }
    double t0 = (lo - p) / d, t1 = (hi - p) / d;
    if (t0 > t1) std::swap(t0, t1);
    s_in = std::max(s_in, t0);
    s_out = std::min(s_out, t1);
  };
  slab(p_w.x(), dx, ox, x_max);
  slab(p_w.y(), dy, oy, y_max);
  const double s_begin = std::max(s_in, options_.min_range_m);
  const double s_end = s_out;
  if (!(s_end > s_begin)) return out;

  const double zc = p_w.z();
  double best = -kHalfPi, best_s = 0.0;
  bool found = false;
  ElevationLine best_line;  // a sample below it cannot beat best
  const auto set_best = [&](double e) {
    best = e;
    best_line.Set(e);
  };
  // Highest elevation of terrain next to the map's end (a hole, the border): if it comes within
  // tol of the horizon, the horizon may be truncated.
  double edge = -kHalfPi;
  bool prev_valid = false;
  // The last valid sample (its elevation is computed only if the map ends after it); unknown
  // once a skipped stretch (known lower than best - tol) follows it. After a stretch skipped only
  // because it cannot beat best (it may come within tol of it), the terrain at the stretch's far
  // end, looked up when the map does end there (`last_lazy`).
  double last_z = 0.0, last_s = 0.0;
  bool last_known = false, last_lazy = false;
  bool first_sample = true;
  double last_sampled_s = -1.0;
  double best_lo = 0.0, best_hi = 0.0;  // the cell holding the best sample
  const auto elevation_at = [&](double z, double s) { return std::atan2(z - zc, s) + kappa * s; };
  // The elevation of the terrain a distance s along the ray at azimuth (sin, cos) = (ex, ey); the
  // lowest possible off the map.
  const auto elevation_along = [&](double ex, double ey, double s) {
    const auto z = grid_.UpAt(p_w.x() + s * ex, p_w.y() + s * ey);
    return z ? elevation_at(*z, s) : -kHalfPi;
  };

  // The map ends after the last valid sample: its elevation is a candidate for the edge.
  const auto close_edge = [&]() {
    if (!prev_valid || !last_known) return;
    if (last_lazy) {
      // The last valid of the samples the march takes in the stretch's last cell (its far end,
      // its middle, its entry: the far end may lie on the border of the hole that follows).
      const double xe = p_w.x() + last_s * dx - 1e-9 * dx, ye = p_w.y() + last_s * dy - 1e-9 * dy;
      const double i = std::floor((xe - ox) / sp), j = std::floor((ye - oy) / sp);
      double entry = 0.0;
      if (dx > 1e-15) entry = std::max(entry, (ox + i * sp - p_w.x()) / dx);
      if (dx < -1e-15) entry = std::max(entry, (ox + (i + 1) * sp - p_w.x()) / dx);
      if (dy > 1e-15) entry = std::max(entry, (oy + j * sp - p_w.y()) / dy);
      if (dy < -1e-15) entry = std::max(entry, (oy + (j + 1) * sp - p_w.y()) / dy);
      entry += 1e-6;
      bool any = false;
      for (const double si : {last_s, 0.5 * (entry + last_s), entry}) {
        const auto z = grid_.UpAt(p_w.x() + si * dx, p_w.y() + si * dy);
        if (!z) continue;
        last_z = *z;
        last_s = si;
        any = true;
        break;
      }
      last_lazy = false;
      if (!any) return;
    }
    edge = std::max(edge, elevation_at(last_z, last_s));
  };

  const auto sample = [&](double s) {
    if (s == last_sampled_s) return;
    last_sampled_s = s;
    const auto z = grid_.UpAt(p_w.x() + s * dx, p_w.y() + s * dy);
    if (!z) {
      close_edge();
      prev_valid = false;
      first_sample = false;
      return;
    }
    // Valid terrain after a hole, or where the ray enters the map away from the camera.
    if (!prev_valid && (!first_sample || s_in > options_.min_range_m)) {
      edge = std::max(edge, elevation_at(*z, s));
    }
    first_sample = false;
    prev_valid = true;
    last_z = *z;
    last_s = s;
    last_known = true;
    last_lazy = false;
    const double g = (*z - zc) / s;
    if (found && g < best_line.Below(kappa, s)) return;
    const double e = elevation_at(*z, s);
    if (e > best) {
      set_best(e);
      best_s = s;
      found = true;
    }
  };

  // A coarse pass first (every 8 node spacings): any terrain sample is a lower bound of the
  // horizon, so blocks that cannot reach it are skipped from the start instead of sampling
  // every cell of terrain that rises towards the ridge making the horizon.
  ElevationLine floor;
  floor.e = -kHalfPi;
  for (double sc = s_begin; sc < s_end; sc += 8.0 * sp) {
    const auto z = grid_.UpAt(p_w.x() + sc * dx, p_w.y() + sc * dy);
    if (!z || (*z - zc) / sc < floor.Below(kappa, sc)) continue;
    const double e = std::atan2(*z - zc, sc) + kappa * sc;
    if (e > floor.e) floor.Set(e);
  }

  const int top = static_cast<int>(levels_.size()) - 1;
  int level = top;
  // Two thresholds: terrain that cannot come within tol of the horizon so far (skipped, and
  // nothing of it is kept), and terrain that cannot beat the horizon so far (skipped too: it
  // cannot change the maximum; only where the map ends next to it does its elevation matter, for
  // the truncation test, and that is recorded as above). Over the sea the second is what saves
  // the march: the curved sea stays within tol of its own horizon for kilometres either side of
  // it.
  ElevationLine beat, reach;  // the horizon so far (best, or the floor before it), and tol below
  double s = s_begin;
  while (s < s_end) {
    const double x = p_w.x() + s * dx, y = p_w.y() + s * dy;
    const Level& lv = levels_[level];
    const double w = sp * static_cast<double>(1 << level);
    const int i = std::clamp(static_cast<int>(std::floor((x - ox) / w)), 0, lv.cols - 1);
    const int j = std::clamp(static_cast<int>(std::floor((y - oy) / w)), 0, lv.rows - 1);
    double s_exit = s_end;
    if (dx > 1e-15) s_exit = std::min(s_exit, (ox + (i + 1) * w - p_w.x()) / dx);
    if (dx < -1e-15) s_exit = std::min(s_exit, (ox + i * w - p_w.x()) / dx);
    if (dy > 1e-15) s_exit = std::min(s_exit, (oy + (j + 1) * w - p_w.y()) / dy);
    if (dy < -1e-15) s_exit = std::min(s_exit, (oy + j * w - p_w.y()) / dy);
    s_exit = std::max(s_exit, s);
    const float block_max = lv.max[static_cast<size_t>(j) * lv.cols + i];
    if (beat.e != std::max(best, floor.e)) {
      beat.Set(std::max(best, floor.e));
      reach.Set(beat.e - tol);
    }
    if (reach.e > -kHalfPi + 1e-3) {
      // Lowest terrain that could reach a line anywhere on [s, s_exit]: the required
      // z_c + s tan(e - kappa s) is at least z_c + s T with T = line.Below at s_exit.
      const auto lowest = [&](const ElevationLine& line) {
        const double t = line.Below(kappa, s_exit);
        return zc + std::min(s * t, s_exit * t);
      };
      if (block_max < lowest(reach)) {
        s = s_exit + 1e-6;
        last_known = false;
        if (level < top) ++level;
        continue;
      }
      // The same bound for best itself (a finite block_max: no hole inside the block).
      if (block_max < lowest(beat)) {
        // What sampling the block would have recorded: an edge at its entry when the map
        // resumes there (or at its middle, when the entry lies on a void's border), and its far
        // end as the last valid terrain.
        if (!prev_valid) sample(s);
        if (!prev_valid) sample(0.5 * (s + s_exit));
        if (prev_valid) {
          last_s = s_exit;
          last_known = true;
          last_lazy = true;
        }
        s = s_exit + 1e-6;
        if (level < top) ++level;
        continue;
      }
    }
    if (level > 0) {
      --level;
      continue;
    }
    const double before = best;
    sample(s);
    sample(0.5 * (s + s_exit));
    sample(s_exit);
    if (best > before) {
      best_lo = s;
      best_hi = s_exit;
    }
    s = s_exit + 1e-6;
  }
  // Where the ray stops (the map's border or max_range) the map ends too.
  close_edge();
  if (!found) return out;

  // The maximum inside the best cell, by golden-section search on the bilinear surface: at an
  // interior maximum d e / d s = 0, which the envelope-theorem derivatives below assume.
  {
    const auto elevation = [&](double si) { return elevation_along(dx, dy, si); };
    const double a = std::max({best_lo, best_s - 0.5 * sp, s_begin});
    const double b = std::min(best_hi, best_s + 0.5 * sp);
    const GoldenBracket found_max = GoldenSectionMax(elevation, a, b, 24);
    const double sm = 0.5 * (found_max.a + found_max.b);
    const double em = elevation(sm);
    if (em > best) {
      set_best(em);
      best_s = sm;
    }
  }

  out.valid = true;
  out.elevation_rad = best;
  out.distance_m = best_s;
  out.truncated = edge >= best - tol;
  const double px = p_w.x() + best_s * dx, py = p_w.y() + best_s * dy;
  const auto z_at = grid_.UpAt(px, py);
  const double z = z_at ? *z_at : zc + best_s * std::tan(best - kappa * best_s);
  out.point_w = Eigen::Vector3d(px, py, z);
  // The refraction term k s / (2 R) at fixed s* (Hirt et al. 2010, eq. 2).
  out.d_elevation_d_refraction = best_s / (2.0 * options_.earth_radius_m);
  if (!derivatives) return out;
  // The derivatives of the maximum, which slides along the ridge as the camera moves. On the
  // bilinear surface of a DEM the maximum along a ray mostly sits on a kink where the ray crosses
  // a grid line; the terrain's gradient there is undefined, and a gradient averaged across the
  // crest is not the slope the ray grazes. So:
  //  - along the ray the grazed point stays put (a tangent point or a kink, either way):
  //    d e / d s = -dz / (s^2 + dz^2) + kappa for e = atan2(dz, s) + kappa s;
  //  - the skyline's slope d e / d a comes from the maxima re-found next to the point on rays
  //    a +- da (each a local maximum along its ray, sliding along the ridge as the true one does);
  //  - a camera moved by c across the ray sees at azimuth a what it saw at a + c / s.
  const double dz = z - zc;
  const double f = best_s / (best_s * best_s + dz * dz);
  {
    const double half = 1.5 * sp;
    const auto local_max = [&](double az) {
      const double ex = std::sin(az), ey = std::cos(az);
      const auto elevation = [&](double si) { return elevation_along(ex, ey, si); };
      const double a = std::max(best_s - half, s_begin), b = std::min(best_s + half, s_end);
      // The best of a few samples first, so that the search brackets the ridge's crest and not a
      // lower bump next to it, then golden-section search around it.
      constexpr int kSamples = 12;
      double top = -kHalfPi, top_s = best_s;
      for (int k = 0; k <= kSamples; ++k) {
        const double si = a + (b - a) * k / kSamples;
        const double ei = elevation(si);
        if (ei > top) {
          top = ei;
          top_s = si;
        }
      }
      const double step = (b - a) / kSamples;
      return std::max(
          top, GoldenSectionMax(elevation, std::max(a, top_s - step), std::min(b, top_s + step), 20)
                   .best);
    };
    const double da = 0.25 * sp / best_s;
    const double plus = local_max(azimuth_rad + da), minus = local_max(azimuth_rad - da);
    out.d_elevation_d_azimuth =
        plus > -kHalfPi && minus > -kHalfPi ? (plus - minus) / (2.0 * da) : 0.0;
  }
  const double along = dz / (best_s * best_s + dz * dz) - kappa;
  const double across = out.d_elevation_d_azimuth / best_s;
  out.d_elevation_d_p = Eigen::Vector3d(along * dx + across * dy, along * dy - across * dx, -f);
  return out;
}

std::vector<HorizonSample> HorizonPredictor::Profile(const Eigen::Vector3d& p_w,
                                                     double azimuth0_rad,
                                                     double step_rad,
                                                     int n) const {
  std::vector<HorizonSample> out;
  out.reserve(std::max(n, 0));
  for (int i = 0; i < n; ++i) out.push_back(Trace(p_w, azimuth0_rad + i * step_rad));
  return out;
}

}  // namespace skerry::skyline
