#include "skerry/sim/harbour_world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "random.h"

namespace skerry::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

Eigen::Matrix3d Yaw(double yaw_rad) {
  return Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// The footprint's axis-aligned bounds.
Eigen::AlignedBox2d Footprint(const OrientedBox& b) {
  const Eigen::Vector2d half = b.R_w_box.topRows<2>().cwiseAbs() * b.half_size_m;
  return Eigen::AlignedBox2d(b.centre_w.head<2>() - half, b.centre_w.head<2>() + half);
}

}  // namespace

const char* HarbourObjectKindName(HarbourObjectKind kind) {
  switch (kind) {
    case HarbourObjectKind::kQuay:
      return "quay";
    case HarbourObjectKind::kPier:
      return "pier";
    case HarbourObjectKind::kBreakwater:
      return "breakwater";
    case HarbourObjectKind::kBuilding:
      return "building";
    case HarbourObjectKind::kBoat:
      return "boat";
    case HarbourObjectKind::kBollard:
      return "bollard";
    case HarbourObjectKind::kPole:
      return "pole";
    case HarbourObjectKind::kCraneLeg:
      return "crane leg";
    case HarbourObjectKind::kCraneBeam:
      return "crane beam";
    case HarbourObjectKind::kMarking:
      return "marking";
  }
  return "?";
}

bool IsTerrain(HarbourObjectKind kind) {
  return kind == HarbourObjectKind::kQuay || kind == HarbourObjectKind::kPier ||
         kind == HarbourObjectKind::kBreakwater || kind == HarbourObjectKind::kMarking;
}

OrientedBox ToOrientedBox(const HarbourBox& box) {
  OrientedBox o;
  o.centre_w =
      Eigen::Vector3d(box.centre_w.x(), box.centre_w.y(), 0.5 * (box.bottom_m + box.top_m));
  o.R_w_box = Yaw(box.yaw_rad);
  o.half_size_m = 0.5 * Eigen::Vector3d(box.length_m, box.width_m, box.top_m - box.bottom_m);
  return o;
}

std::optional<RayHit> RaycastBox(const OrientedBox& box,
                                 const Eigen::Vector3d& origin,
                                 const Eigen::Vector3d& direction,
                                 double max_range_m) {
  // Slab method in the box's frame: the ray is inside slab i for t between its two crossings of
  // the planes +-h_i; it is inside the box where all three intervals overlap.
  const Eigen::Vector3d o = box.R_w_box.transpose() * (origin - box.centre_w);
  const Eigen::Vector3d d = box.R_w_box.transpose() * direction;
  double t_enter = -kInf;
  double t_exit = kInf;
  int enter_axis = -1;
  for (int i = 0; i < 3; ++i) {
    const double h = box.half_size_m[i];
    if (std::abs(d[i]) < 1e-12) {
      // Parallel to the slab: inside it (strictly: along a face is a touch, not a hit) or never.
      if (!(o[i] > -h && o[i] < h)) return std::nullopt;
      continue;
    }
    double t1 = (-h - o[i]) / d[i];
    double t2 = (h - o[i]) / d[i];
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > t_enter) {
      t_enter = t1;
      enter_axis = i;
    }
    t_exit = std::min(t_exit, t2);
  }
  // A touch (t_enter == t_exit), a start inside (t_enter <= 0), behind, or beyond the range.
  if (enter_axis < 0 || !(t_enter < t_exit) || !(t_enter > 0.0) || t_enter > max_range_m) {
    return std::nullopt;
  }
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[enter_axis] = d[enter_axis] > 0.0 ? -1.0 : 1.0;
  RayHit hit;
  hit.range_m = t_enter;
  hit.point_w = origin + t_enter * direction;
  hit.normal_w = box.R_w_box * n;
  return hit;
}

bool BoxesOverlap(const OrientedBox& a, const OrientedBox& b) {
  // Ericson 2005, sec. 4.4.1: R expresses b's axes in a's frame, t the centre offset in a's
  // frame; an epsilon on |R| keeps near-parallel edge pairs (cross products ~ 0) robust.
  const Eigen::Matrix3d R = a.R_w_box.transpose() * b.R_w_box;
  const Eigen::Vector3d t = a.R_w_box.transpose() * (b.centre_w - a.centre_w);
  const Eigen::Matrix3d abs_R = R.cwiseAbs().array() + 1e-9;
  const Eigen::Vector3d& ha = a.half_size_m;
  const Eigen::Vector3d& hb = b.half_size_m;
  for (int i = 0; i < 3; ++i) {  // a's axes
    if (std::abs(t[i]) > ha[i] + hb.dot(abs_R.row(i))) return false;
  }
  for (int j = 0; j < 3; ++j) {  // b's axes
    if (std::abs(t.dot(R.col(j))) > ha.dot(abs_R.col(j)) + hb[j]) return false;
  }
  for (int i = 0; i < 3; ++i) {  // a_i x b_j
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const double ra = ha[i1] * abs_R(i2, j) + ha[i2] * abs_R(i1, j);
      const double rb = hb[j1] * abs_R(i, j2) + hb[j2] * abs_R(i, j1);
      if (std::abs(t[i2] * R(i1, j) - t[i1] * R(i2, j)) > ra + rb) return false;
    }
  }
  return true;
}

HarbourWorld::HarbourWorld(std::vector<HarbourBox> boxes, double water_level_m, double cell_m)
    : boxes_(std::move(boxes)),
      water_level_m_(water_level_m),
      max_top_m_(water_level_m),
      cell_m_(cell_m) {
  if (!(cell_m > 0.0)) throw std::invalid_argument("HarbourWorld: cell size must be > 0");
  for (const HarbourBox& b : boxes_) {
    if (!(b.length_m > 0.0) || !(b.width_m > 0.0) || !(b.top_m > b.bottom_m) ||
        !std::isfinite(b.centre_w.sum() + b.yaw_rad + b.top_m + b.bottom_m)) {
      throw std::invalid_argument(std::string("HarbourWorld: a ") + HarbourObjectKindName(b.kind) +
                                  " box has a non-positive or non-finite size");
    }
    oriented_.push_back(ToOrientedBox(b));
    bounds_.extend(Footprint(oriented_.back()));
    max_top_m_ = std::max(max_top_m_, b.top_m);
  }
  if (boxes_.empty())
    bounds_ = Eigen::AlignedBox2d(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero());
  grid_origin_ = bounds_.min();
  nx_ = std::max(1, static_cast<int>(std::ceil(bounds_.sizes().x() / cell_m_)));
  ny_ = std::max(1, static_cast<int>(std::ceil(bounds_.sizes().y() / cell_m_)));
  cells_.resize(static_cast<size_t>(nx_) * ny_);
  for (size_t k = 0; k < boxes_.size(); ++k) {
    int i0, j0, i1, j1;
    CellRange(Footprint(oriented_[k]), &i0, &j0, &i1, &j1);
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        Cell& c = cells_[static_cast<size_t>(j) * nx_ + i];
        c.boxes.push_back(static_cast<int>(k));
        c.max_top_m = std::max(c.max_top_m, boxes_[k].top_m);
      }
    }
  }
}

void HarbourWorld::CellRange(
    const Eigen::AlignedBox2d& region, int* i0, int* j0, int* i1, int* j1) const {
  auto index = [this](double v, double origin, int n) {
    return std::clamp(static_cast<int>(std::floor((v - origin) / cell_m_)), 0, n - 1);
  };
  *i0 = index(region.min().x(), grid_origin_.x(), nx_);
  *i1 = index(region.max().x(), grid_origin_.x(), nx_);
  *j0 = index(region.min().y(), grid_origin_.y(), ny_);
  *j1 = index(region.max().y(), grid_origin_.y(), ny_);
}

bool HarbourWorld::Sees(const HarbourBox& b, WorldView view) const {
  switch (view) {
    case WorldView::kLidar:
      return b.in_lidar;
    case WorldView::kImage:
      return b.in_image;
    case WorldView::kAll:
      return true;
  }
  return true;
}

std::optional<RayHit> HarbourWorld::Raycast(const Eigen::Vector3d& origin_w,
                                            const Eigen::Vector3d& direction_w,
                                            double max_range_m,
                                            WorldView view) const {
  const double norm = direction_w.norm();
  if (!(norm > 0.0) || boxes_.empty() || !(origin_w.z() >= water_level_m_)) return std::nullopt;
  const Eigen::Vector3d d = direction_w / norm;
  const Eigen::Vector3d& o = origin_w;
  // The part of the ray that can meet a box: above the water, below the tallest top.
  double t_lo = 0.0;
  double t_hi = max_range_m;
  if (d.z() < 0.0) t_hi = std::min(t_hi, (water_level_m_ - o.z()) / d.z());
  if (o.z() > max_top_m_) {
    if (!(d.z() < 0.0)) return std::nullopt;
    t_lo = (max_top_m_ - o.z()) / d.z();
  } else if (d.z() > 0.0) {
    t_hi = std::min(t_hi, (max_top_m_ - o.z()) / d.z());
  }
  // ... and over the grid.
  const Eigen::Vector2d grid_max = grid_origin_ + cell_m_ * Eigen::Vector2d(nx_, ny_);
  for (int a = 0; a < 2; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < grid_origin_[a] || o[a] > grid_max[a]) return std::nullopt;
      continue;
    }
    double t1 = (grid_origin_[a] - o[a]) / d[a];
    double t2 = (grid_max[a] - o[a]) / d[a];
    if (t1 > t2) std::swap(t1, t2);
    t_lo = std::max(t_lo, t1);
    t_hi = std::min(t_hi, t2);
  }
  if (!(t_lo <= t_hi)) return std::nullopt;

  // 2-D DDA (Amanatides and Woo 1987) from the cell holding the ray at t_lo.
  const Eigen::Vector3d start = o + t_lo * d;
  int i = std::clamp(static_cast<int>(std::floor((start.x() - grid_origin_.x()) / cell_m_)), 0,
                     nx_ - 1);
  int j = std::clamp(static_cast<int>(std::floor((start.y() - grid_origin_.y()) / cell_m_)), 0,
                     ny_ - 1);
  const int step_i = d.x() > 0.0 ? 1 : -1;
  const int step_j = d.y() > 0.0 ? 1 : -1;
  auto next_boundary = [&](int index, int step, double origin, double o_a, double d_a) {
    if (d_a == 0.0) return kInf;
    const double edge = origin + cell_m_ * (step > 0 ? index + 1 : index);
    return (edge - o_a) / d_a;
  };
  double t_next_x = next_boundary(i, step_i, grid_origin_.x(), o.x(), d.x());
  double t_next_y = next_boundary(j, step_j, grid_origin_.y(), o.y(), d.y());
  const double dt_x = d.x() == 0.0 ? kInf : cell_m_ / std::abs(d.x());
  const double dt_y = d.y() == 0.0 ? kInf : cell_m_ / std::abs(d.y());

  std::optional<RayHit> best;
  double best_t = t_hi;
  double t_in = t_lo;
  while (true) {
    const double t_out = std::min({t_next_x, t_next_y, t_hi});
    const Cell& cell = cells_[static_cast<size_t>(j) * nx_ + i];
    // The lowest point of the ray inside the cell; nothing to meet when it is above every top.
    const double z_min = o.z() + d.z() * (d.z() < 0.0 ? t_out : t_in);
    if (!cell.boxes.empty() && z_min <= cell.max_top_m) {
      for (const int k : cell.boxes) {
        if (!Sees(boxes_[k], view)) continue;
        std::optional<RayHit> hit = RaycastBox(oriented_[k], o, d, best_t);
        if (hit && (!best || hit->range_m < best->range_m)) {
          hit->box = k;
          hit->reflectivity = boxes_[k].reflectivity;
          best_t = hit->range_m;
          best = hit;
        }
      }
    }
    if ((best && best_t <= t_out) || t_out >= t_hi) break;
    if (t_next_x < t_next_y) {
      i += step_i;
      t_in = t_next_x;
      t_next_x += dt_x;
    } else {
      j += step_j;
      t_in = t_next_y;
      t_next_y += dt_y;
    }
    if (i < 0 || i >= nx_ || j < 0 || j >= ny_) break;
  }
  return best;
}

bool HarbourWorld::Intersects(const OrientedBox& box, WorldView view) const {
  if (boxes_.empty()) return false;
  const Eigen::AlignedBox2d region = Footprint(box);
  if (!region.intersects(bounds_)) return false;
  int i0, j0, i1, j1;
  CellRange(region, &i0, &j0, &i1, &j1);
  std::vector<char> tested(boxes_.size(), 0);
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      for (const int k : cells_[static_cast<size_t>(j) * nx_ + i].boxes) {
        if (tested[k] || !Sees(boxes_[k], view)) continue;
        tested[k] = 1;
        if (BoxesOverlap(box, oriented_[k])) return true;
      }
    }
  }
  return false;
}

double HarbourWorld::TerrainHeight(const Eigen::Vector2d& p_w, WorldView view) const {
  double z = water_level_m_;
  if (boxes_.empty() || !bounds_.contains(p_w)) return z;
  int i0, j0, i1, j1;
  CellRange(Eigen::AlignedBox2d(p_w, p_w), &i0, &j0, &i1, &j1);
  for (const int k : cells_[static_cast<size_t>(j0) * nx_ + i0].boxes) {
    const HarbourBox& b = boxes_[k];
    if (!IsTerrain(b.kind) || !Sees(b, view) || !(b.top_m > z)) continue;
    const Eigen::Vector2d q =
        oriented_[k].R_w_box.topLeftCorner<2, 2>().transpose() * (p_w - b.centre_w);
    if (std::abs(q.x()) <= 0.5 * b.length_m && std::abs(q.y()) <= 0.5 * b.width_m) z = b.top_m;
  }
  return z;
}

// --- The built-in layout. -------------------------------------------------------------------
namespace {

// Boxes in the harbour's own frame (x east, y north, origin at the basin's centre, heights
// above the water), placed into w at the end.
class LayoutBuilder {
 public:
  explicit LayoutBuilder(double water_level_m) : water_(water_level_m) {}

  HarbourBox& Add(HarbourObjectKind kind,
                  double cx,
                  double cy,
                  double yaw_rad,
                  double length_m,
                  double width_m,
                  double bottom_m,
                  double top_m,
                  double albedo,
                  double reflectivity) {
    HarbourBox b;
    b.kind = kind;
    b.centre_w = Eigen::Vector2d(cx, cy);
    b.yaw_rad = yaw_rad;
    b.length_m = length_m;
    b.width_m = width_m;
    b.bottom_m = water_ + bottom_m;
    b.top_m = water_ + top_m;
    b.albedo = albedo;
    b.reflectivity = reflectivity;
    boxes_.push_back(b);
    return boxes_.back();
  }

  // An axis-aligned rectangle [x0, x1] x [y0, y1].
  HarbourBox& Rect(HarbourObjectKind kind,
                   double x0,
                   double x1,
                   double y0,
                   double y1,
                   double bottom_m,
                   double top_m,
                   double albedo,
                   double reflectivity) {
    return Add(kind, 0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.0, x1 - x0, y1 - y0, bottom_m, top_m,
               albedo, reflectivity);
  }

  std::vector<HarbourBox>& boxes() { return boxes_; }

 private:
  double water_;
  std::vector<HarbourBox> boxes_;
};

// A stretch of quay wall where boats can lie: from `start` along `along` for `length`, the
// water on the side of `out`.
struct Berth {
  Eigen::Vector2d start;
  Eigen::Vector2d along;
  Eigen::Vector2d out;
  double length;
};

// Where the channel's centre line and the entrance's middle lie: x = these times half the basin.
constexpr double kChannelX = 0.4;
constexpr double kEntranceX = 0.6;

// The harbour's own frame -> w: turned by rotation_deg about the basin's centre, then moved to
// it.
Eigen::Vector2d ToWorld(const HarbourSpec& spec, const Eigen::Vector2d& local) {
  return Eigen::Vector2d(spec.centre_east_m, spec.centre_north_m) +
         Eigen::Rotation2Dd(spec.rotation_deg * kPi / 180.0) * local;
}

}  // namespace

HarbourLayout HarbourLayoutOf(const HarbourSpec& spec) {
  // The same numbers as BuildHarbour's.
  const double b = 0.5 * spec.basin_size_m;
  HarbourLayout l;
  l.basin_centre_w = ToWorld(spec, {0.0, 0.0});
  l.basin_size_m = spec.basin_size_m;
  l.channel_mouth_w = ToWorld(spec, {kChannelX * b, b});
  l.channel_end_w = ToWorld(spec, {kChannelX * b, b + spec.channel_length_m});
  l.channel_width_m = spec.channel_width_m;
  l.entrance_w = ToWorld(spec, {kEntranceX * b, -b});
  l.entrance_width_m = spec.entrance_width_m;
  return l;
}

HarbourWorld BuildHarbour(const HarbourSpec& spec, std::uint64_t seed) {
  using K = HarbourObjectKind;
  const double b = 0.5 * spec.basin_size_m;  // the basin is [-b, b]^2
  const double hq = spec.quay_height_m;
  const double land = 60.0;        // depth of the land behind the quays
  const double bank = 40.0;        // width of each bank along the channel
  const double underwater = -6.0;  // bottom of every solid standing in the water
  const double xc0 = kChannelX * b - 0.5 * spec.channel_width_m;  // channel: x from xc0 to xc1
  const double xc1 = kChannelX * b + 0.5 * spec.channel_width_m;
  const double y_channel_end = b + spec.channel_length_m;
  const double xe0 = kEntranceX * b - 0.5 * spec.entrance_width_m;  // entrance: xe0 to xe1
  const double xe1 = kEntranceX * b + 0.5 * spec.entrance_width_m;
  const double breakwater = 12.0;

  LayoutBuilder L(spec.water_level_up_m);
  // Land behind the quays (west, north either side of the channel, east) and the channel's banks.
  L.Rect(K::kQuay, -b - land, -b, -b, b + land, underwater, hq, 0.42, 0.35);
  L.Rect(K::kQuay, -b, xc0, b, b + land, underwater, hq, 0.42, 0.35);
  L.Rect(K::kQuay, xc1, b + land, b, b + land, underwater, hq, 0.42, 0.35);
  L.Rect(K::kQuay, b, b + land, -b, b, underwater, hq, 0.42, 0.35);
  if (y_channel_end > b + land) {
    L.Rect(K::kQuay, xc0 - bank, xc0, b + land, y_channel_end, underwater, hq, 0.45, 0.35);
    L.Rect(K::kQuay, xc1, xc1 + bank, b + land, y_channel_end, underwater, hq, 0.45, 0.35);
  }
  // The breakwater and the east mole, with the entrance between them.
  L.Rect(K::kBreakwater, -b - land, xe0, -b - breakwater, -b, underwater, 3.5, 0.55, 0.3);
  L.Rect(K::kBreakwater, xe1, b + land, -b - breakwater, -b, underwater, 3.0, 0.55, 0.3);

  // Piers: two from the north quay, a third from the west quay.
  const double pier_length = 0.32 * spec.basin_size_m;
  const double pier_width = 10.0;
  const double pier_top = hq - 0.3;
  std::vector<Berth> berths;
  std::vector<double> north_pier_x;
  for (int k = 0; k < spec.piers; ++k) {
    if (k < 2) {
      const double x = k == 0 ? -0.6 * b : -0.12 * b;
      north_pier_x.push_back(x);
      L.Rect(K::kPier, x - 0.5 * pier_width, x + 0.5 * pier_width, b - pier_length, b, underwater,
             pier_top, 0.58, 0.4);
      for (const double side : {-1.0, 1.0}) {
        berths.push_back(
            {{x + side * 0.5 * pier_width, b - 8.0}, {0.0, -1.0}, {side, 0.0}, pier_length - 8.0});
      }
    } else {
      const double y = -0.35 * b;
      L.Rect(K::kPier, -b, -b + pier_length, y - 0.5 * pier_width, y + 0.5 * pier_width, underwater,
             pier_top, 0.58, 0.4);
      for (const double side : {-1.0, 1.0}) {
        berths.push_back(
            {{-b + 8.0, y + side * 0.5 * pier_width}, {1.0, 0.0}, {0.0, side}, pier_length - 8.0});
      }
    }
  }

  // Buildings and warehouses on the land, set back from the quay edges.
  const double deg = kPi / 180.0;
  struct Building {
    double cx, cy, yaw_deg, length, width, height, albedo;
  };
  const Building buildings[] = {
      {-b - 0.5 * land, 0.3 * b, 90, 45, 22, 10, 0.62},  // warehouse, west
      {-b - 25, -0.5 * b, 0, 18, 18, 24, 0.35},          // office tower, west
      {-b - 30, b + 25, 0, 25, 15, 6, 0.72},             // shed, north-west corner
      {-0.55 * b, b + 32, 0, 50, 20, 12, 0.55},          // warehouse, north
      {-0.05 * b, b + 30, 0, 25, 18, 8, 0.3},            // harbour office, north
      {0.85 * b, b + 35, 0, 30, 20, 9, 0.68},            // shed, north-east
      {b + 35, 0.05 * b, 90, 60, 20, 11, 0.5},           // warehouse, east
      {b + 30, -0.65 * b, 10, 25, 15, 7, 0.78},          // workshop, east
  };
  for (const Building& s : buildings) {
    L.Add(K::kBuilding, s.cx, s.cy, s.yaw_deg * deg, s.length, s.width, hq - 0.5, hq + s.height,
          s.albedo, 0.5);
  }
  // A gantry crane on the east quay, its beam reaching over the water.
  const double crane_y = 0.5 * b;
  for (const double x : {b + 3.0, b + 15.0}) {
    for (const double dy : {-5.0, 5.0}) {
      L.Add(K::kCraneLeg, x, crane_y + dy, 0.0, 1.0, 1.0, hq - 0.5, hq + 25.0, 0.75, 0.6);
    }
  }
  L.Add(K::kCraneBeam, b - 1.0, crane_y, 0.0, 34.0, 2.5, hq + 25.0, hq + 27.5, 0.75, 0.6);

  // Along the basin's quays: bollards at the edge, light poles behind them, a painted line.
  struct Edge {
    Eigen::Vector2d start, along, in;  // in: towards the land
    double length;
  };
  std::vector<Edge> edges = {
      {{-b, -b + 10}, {0, 1}, {-1, 0}, 2 * b - 20},         // west quay
      {{-b + 10, b}, {1, 0}, {0, 1}, xc0 - 8 - (-b + 10)},  // north quay, west of the channel
      {{xc1 + 8, b}, {1, 0}, {0, 1}, b - 10 - (xc1 + 8)},   // north quay, east of it
      {{b, -b + 10}, {0, 1}, {1, 0}, 2 * b - 20},           // east quay
  };
  for (const Edge& e : edges) {
    if (e.length <= 0.0) continue;
    const double yaw = std::atan2(e.along.y(), e.along.x());
    for (double s = 0.0; s <= e.length; s += 20.0) {
      const Eigen::Vector2d p = e.start + s * e.along + 0.8 * e.in;
      L.Add(K::kBollard, p.x(), p.y(), yaw, 0.4, 0.4, hq - 0.2, hq + 0.5, 0.2, 0.3);
    }
    for (double s = 10.0; s <= e.length; s += 45.0) {
      const Eigen::Vector2d p = e.start + s * e.along + 6.0 * e.in;
      L.Add(K::kPole, p.x(), p.y(), yaw, 0.3, 0.3, hq - 0.2, hq + 9.0, 0.6, 0.7);
    }
    const Eigen::Vector2d c = e.start + 0.5 * e.length * e.along + 3.0 * e.in;
    L.Add(K::kMarking, c.x(), c.y(), yaw, e.length, 0.3, hq - 0.1, hq + 0.02, 0.92, 0.85);
  }
  // Parking bays on the west land: short painted lines.
  for (int k = 0; k < 16; ++k) {
    L.Add(K::kMarking, -b - 12.0, -20.0 + 2.6 * k, 0.0, 5.0, 0.15, hq - 0.1, hq + 0.02, 0.92, 0.85);
  }
  // Bollards along the piers.
  const size_t pier_berths = berths.size();
  for (size_t k = 0; k < pier_berths; ++k) {
    const Berth& p = berths[k];
    const double yaw = std::atan2(p.along.y(), p.along.x());
    for (double s = 2.0; s <= p.length; s += 20.0) {
      const Eigen::Vector2d q = p.start + s * p.along - 0.8 * p.out;
      L.Add(K::kBollard, q.x(), q.y(), yaw, 0.4, 0.4, pier_top - 0.2, pier_top + 0.5, 0.2, 0.3);
    }
  }

  // Berths along the quays (the piers' were added above), clear of the pier roots.
  auto add_split = [&berths](Eigen::Vector2d start, Eigen::Vector2d along, Eigen::Vector2d out,
                             double from, double to, std::vector<std::pair<double, double>> gaps) {
    std::sort(gaps.begin(), gaps.end());
    double s = from;
    for (const auto& g : gaps) {
      if (g.first - s > 10.0) berths.push_back({start + s * along, along, out, g.first - s});
      s = std::max(s, g.second);
    }
    if (to - s > 10.0) berths.push_back({start + s * along, along, out, to - s});
  };
  std::vector<std::pair<double, double>> north_gaps;
  for (const double x : north_pier_x) {
    north_gaps.push_back({x - 0.5 * pier_width - 8.0, x + 0.5 * pier_width + 8.0});
  }
  add_split({0.0, b}, {1, 0}, {0, -1}, -b + 10.0, xc0 - 10.0, north_gaps);
  add_split({0.0, b}, {1, 0}, {0, -1}, xc1 + 10.0, b - 10.0, {});
  std::vector<std::pair<double, double>> west_gaps;
  if (spec.piers >= 3) west_gaps.push_back({-0.35 * b - 13.0, -0.35 * b + 13.0});
  add_split({-b, 0.0}, {0, 1}, {1, 0}, -b + 10.0, b - 10.0, west_gaps);
  add_split({b, 0.0}, {0, 1}, {-1, 0}, -b + 10.0, b - 10.0, {});
  add_split({0.0, -b}, {1, 0}, {0, 1}, -b + 10.0, xe0 - 25.0, {});  // inside the breakwater

  // Boats: drawn from the seed along the berths, clear of every boat that shares a world with
  // them (a boat gone since the photograph may have lain where a newcomer lies now).
  Rng rng(seed, RngStream::kHarbourBoats);
  double total = 0.0;
  for (const Berth& berth : berths) total += berth.length;
  struct Placed {
    OrientedBox footprint;
    bool in_image, in_lidar;
  };
  std::vector<Placed> placed;
  auto place = [&](bool in_image, bool in_lidar) {
    for (int attempt = 0; attempt < 400; ++attempt) {
      double pick = rng.Uniform() * total;
      size_t k = 0;
      while (k + 1 < berths.size() && pick > berths[k].length) pick -= berths[k++].length;
      const Berth& berth = berths[k];
      const double length = 8.0 + 14.0 * rng.Uniform();
      const double width = std::clamp(length / 3.3, 2.5, 6.0);
      const double s = rng.Uniform();
      const double gap = 0.8 + 0.6 * rng.Uniform();
      const bool dark_hull = rng.Uniform() < 0.3;
      if (length > berth.length) continue;
      const double along = 0.5 * length + s * (berth.length - length);
      const Eigen::Vector2d c = berth.start + along * berth.along + (gap + 0.5 * width) * berth.out;
      const double yaw = std::atan2(berth.along.y(), berth.along.x());
      OrientedBox footprint;
      footprint.centre_w = Eigen::Vector3d(c.x(), c.y(), 0.0);
      footprint.R_w_box = Yaw(yaw);
      footprint.half_size_m = Eigen::Vector3d(0.5 * length + 1.0, 0.5 * width + 1.0, 1.0);
      const bool clash = std::any_of(placed.begin(), placed.end(), [&](const Placed& p) {
        const bool share = (p.in_image && in_image) || (p.in_lidar && in_lidar);
        return share && BoxesOverlap(p.footprint, footprint);
      });
      if (clash) continue;
      placed.push_back({footprint, in_image, in_lidar});
      // Hull, then a cabin aft of the middle.
      const double freeboard = 1.0 + 0.04 * length;
      HarbourBox& hull = L.Add(K::kBoat, c.x(), c.y(), yaw, length, width, -0.8, freeboard,
                               dark_hull ? 0.35 : 0.85, 0.6);
      hull.in_image = in_image;
      hull.in_lidar = in_lidar;
      const Eigen::Vector2d aft = c - 0.1 * length * berth.along;
      HarbourBox& cabin = L.Add(K::kBoat, aft.x(), aft.y(), yaw, 0.4 * length, 0.75 * width,
                                freeboard - 0.2, freeboard + 1.8 + 0.05 * length, 0.8, 0.55);
      cabin.in_image = in_image;
      cabin.in_lidar = in_lidar;
      return;
    }
    throw std::invalid_argument("BuildHarbour: the boats asked for do not fit along the quays");
  };
  for (int k = 0; k < spec.boats_moored; ++k) place(true, true);
  for (int k = 0; k < spec.boats_image_only; ++k) place(true, false);
  for (int k = 0; k < spec.boats_lidar_only; ++k) place(false, true);

  // Into w.
  std::vector<HarbourBox>& boxes = L.boxes();
  for (HarbourBox& box : boxes) {
    box.centre_w = ToWorld(spec, box.centre_w);
    box.yaw_rad += spec.rotation_deg * deg;
  }
  return HarbourWorld(std::move(boxes), spec.water_level_up_m);
}

}  // namespace skerry::sim
