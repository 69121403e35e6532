#include "skerry/eval/allan_deviation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>

#include "skerry/io/atomic_file.h"

namespace skerry {

namespace {

/// sqrt(2 ln 2 / pi): the Allan deviation floor of flicker rate noise of coefficient B is 0.664 B
/// (IEEE Std 952-1997 C.1.3).
constexpr double kFlickerFloor = 0.664;

/// Local slopes are least-squares slopes over the points within this many decades of tau.
constexpr double kSlopeHalfWindowDecades = 0.2;

/// The slope bands that make a region: white rate noise -1/2, rate random walk +1/2.
constexpr double kWhiteSlope = -0.5, kWhiteSlopeTol = 0.2;
constexpr size_t kWhiteStartPoints = 3;
constexpr double kRandomWalkSlope = 0.5, kRandomWalkSlopeTol = 0.25;

bool Usable(const AllanPoint& p) { return p.adev > 0.0 && std::isfinite(p.adev); }

/// d ln(adev) / d ln(tau) at every point: the least-squares line through the points within
/// kSlopeHalfWindowDecades (at least the neighbours on each side). NaN where it is not defined.
std::vector<double> LocalSlopes(const std::vector<AllanPoint>& c) {
  const size_t n = c.size();
  std::vector<double> slopes(n, std::numeric_limits<double>::quiet_NaN());
  for (size_t i = 0; i < n; ++i) {
    if (!Usable(c[i])) continue;
    const double li = std::log10(c[i].tau_s);
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int count = 0;
    for (size_t j = 0; j < n; ++j) {
      if (!Usable(c[j])) continue;
      const double lj = std::log10(c[j].tau_s);
      const bool neighbour = j + 1 == i || j == i + 1;
      if (std::abs(lj - li) > kSlopeHalfWindowDecades && !neighbour) continue;
      const double y = std::log10(c[j].adev);
      sx += lj;
      sy += y;
      sxx += lj * lj;
      sxy += lj * y;
      ++count;
    }
    const double den = count * sxx - sx * sx;
    if (count >= 2 && den > 0.0) slopes[i] = (count * sxy - sx * sy) / den;
  }
  return slopes;
}

/// y_i = p f_i by least squares weighted with 1 / sigma_i^2. The points of one Allan curve share
/// their data, so their errors are far from independent: the sigma of p is propagated as if they
/// were fully correlated, sigma_p = sum_i c_i sigma_i with p = sum_i c_i y_i (an upper bound;
/// independence would understate it by about the square root of the number of points).
IdentifiedValue FitProportional(const std::vector<double>& f,
                                const std::vector<double>& y,
                                const std::vector<double>& sigma) {
  double sff = 0.0;
  for (size_t i = 0; i < f.size(); ++i) sff += f[i] * f[i] / (sigma[i] * sigma[i]);
  IdentifiedValue v;
  for (size_t i = 0; i < f.size(); ++i) {
    const double c = f[i] / (sigma[i] * sigma[i]) / sff;
    v.value += c * y[i];
    v.sigma += c * sigma[i];
  }
  v.identified = !f.empty();
  return v;
}

/// The RMS over the three axes, its sigma propagated from the axes' (independent errors).
IdentifiedValue RmsOfAxes(const IdentifiedValue& a,
                          const IdentifiedValue& b,
                          const IdentifiedValue& c) {
  const IdentifiedValue* axes[3] = {&a, &b, &c};
  double sum_sq = 0.0, sum_sigma_sq = 0.0;
  bool identified = true;
  for (const IdentifiedValue* v : axes) {
    sum_sq += v->value * v->value;
    sum_sigma_sq += v->sigma * v->sigma;
    identified = identified && v->identified;
  }
  IdentifiedValue r;
  r.value = std::sqrt(sum_sq / 3.0);
  r.identified = identified;
  if (r.value > 0.0) {
    // d rms / d v_i = v_i / (3 rms).
    double var = 0.0;
    for (const IdentifiedValue* v : axes) {
      const double d = v->value / (3.0 * r.value);
      var += d * d * v->sigma * v->sigma;
    }
    r.sigma = std::sqrt(var);
  } else {
    r.sigma = std::sqrt(sum_sigma_sq / 3.0);  // no gradient at 0: the scale of the axes' errors
  }
  return r;
}

AllanFit Combine(const std::array<AllanFit, 3>& f) {
  AllanFit c;
  c.white_density = RmsOfAxes(f[0].white_density, f[1].white_density, f[2].white_density);
  c.bias_instability =
      RmsOfAxes(f[0].bias_instability, f[1].bias_instability, f[2].bias_instability);
  c.random_walk = RmsOfAxes(f[0].random_walk, f[1].random_walk, f[2].random_walk);
  std::array<double, 3> taus = {f[0].min_tau_s, f[1].min_tau_s, f[2].min_tau_s};
  std::sort(taus.begin(), taus.end());
  c.min_tau_s = taus[1];
  return c;
}

/// The median of the positive intervals between consecutive samples [begin, end); 0 if none.
double MedianIntervalS(const std::vector<ImuSample>& imu, size_t begin, size_t end) {
  std::vector<TimeNs> dt;
  for (size_t i = begin + 1; i < end; ++i) {
    if (imu[i].t_ns > imu[i - 1].t_ns) dt.push_back(imu[i].t_ns - imu[i - 1].t_ns);
  }
  if (dt.empty()) return 0.0;
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  return NsToSeconds(dt[dt.size() / 2]);
}

}  // namespace

std::vector<AllanPoint> OverlappingAllanDeviation(const std::vector<double>& x,
                                                  double rate_hz,
                                                  int points_per_decade) {
  const size_t n = x.size();
  if (n < 20) {
    throw std::invalid_argument("OverlappingAllanDeviation: " + std::to_string(n) +
                                " samples, at least 20 needed");
  }
  if (!std::isfinite(rate_hz) || rate_hz <= 0.0) {
    throw std::invalid_argument("OverlappingAllanDeviation: rate_hz must be finite and > 0");
  }
  if (points_per_decade < 1) {
    throw std::invalid_argument("OverlappingAllanDeviation: points_per_decade < 1");
  }
  double mean = 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(x[i])) {
      throw std::invalid_argument("OverlappingAllanDeviation: sample " + std::to_string(i) +
                                  " is not finite");
    }
    mean += x[i];
  }
  mean /= static_cast<double>(n);
  // theta_k = sum_{i<k} (x_i - mean), in samples (tau0 = 1): the Allan variance does not see a
  // constant, and without it theta would grow to where its differences lose their digits.
  std::vector<double> theta(n + 1, 0.0);
  long double sum = 0.0L;
  for (size_t i = 0; i < n; ++i) {
    sum += static_cast<long double>(x[i] - mean);
    theta[i + 1] = static_cast<double>(sum);
  }

  std::vector<AllanPoint> curve;
  const size_t m_max = n / 9;
  size_t last_m = 0;
  for (int i = 0;; ++i) {
    const auto m = static_cast<size_t>(
        std::llround(std::pow(10.0, static_cast<double>(i) / points_per_decade)));
    if (m > m_max) break;
    if (m == last_m) continue;
    last_m = m;
    // The cluster means are ybar_k = (theta_{k+m} - theta_k) / m, k = 0..n-m; every overlapping
    // pair (ybar_k, ybar_{k+m}), k = 0..n-2m, enters: sigma^2 = sum (ybar_{k+m} - ybar_k)^2 /
    // (2 (n - 2m + 1)) (IEEE 952 Annex C, the fully overlapping estimator).
    const size_t terms = n - 2 * m + 1;
    double ss = 0.0;
    for (size_t k = 0; k < terms; ++k) {
      const double d = theta[k + 2 * m] - 2.0 * theta[k + m] + theta[k];
      ss += d * d;
    }
    const double md = static_cast<double>(m);
    AllanPoint p;
    p.tau_s = md / rate_hz;
    p.adev = std::sqrt(ss / (2.0 * md * md * static_cast<double>(terms)));
    // El-Sheimy et al. 2008: the percentage error of sigma(tau) from K = N/m clusters is
    // 1 / sqrt(2 (K - 1)).
    const double clusters = static_cast<double>(n) / md;
    p.adev_sigma = p.adev / std::sqrt(2.0 * (clusters - 1.0));
    p.clusters = static_cast<long>(n / m);
    curve.push_back(p);
  }
  return curve;
}

AllanFit FitAllan(const std::vector<AllanPoint>& curve) {
  if (curve.empty()) throw std::invalid_argument("FitAllan: empty curve");
  const size_t n = curve.size();
  const std::vector<double> slope = LocalSlopes(curve);
  size_t i_min = 0;
  for (size_t i = 1; i < n; ++i) {
    if (curve[i].adev < curve[i_min].adev) i_min = i;
  }
  const auto usable = [&](size_t i) { return Usable(curve[i]) && curve[i].adev_sigma > 0.0; };

  AllanFit fit;
  fit.min_tau_s = curve[i_min].tau_s;

  // White rate noise, sigma = N / sqrt(tau): the run of points at slope -1/2 +- 0.2 on the
  // falling side of the curve (up to its minimum), starting among its first kWhiteStartPoints
  // (white noise is what the shortest taus show; a slope of -1/2 only after a rise is the tail of
  // a vibration, not a white density).
  const auto white_slope = [&](size_t j) {
    return std::abs(slope[j] - kWhiteSlope) <= kWhiteSlopeTol && usable(j);
  };
  std::vector<double> f, y, s;
  size_t i = 0;
  while (i < kWhiteStartPoints && i <= i_min && !white_slope(i)) ++i;
  if (i == kWhiteStartPoints) i = i_min + 1;  // no white region
  for (; i <= i_min && white_slope(i); ++i) {
    f.push_back(1.0 / std::sqrt(curve[i].tau_s));
    y.push_back(curve[i].adev);
    s.push_back(curve[i].adev_sigma);
  }
  if (!f.empty()) {
    fit.white_density = FitProportional(f, y, s);
  } else {
    // No slope -1/2 seen: what the shortest tau says, an upper bound when other noise adds there.
    const double root_tau = std::sqrt(curve[0].tau_s);
    fit.white_density = {curve[0].adev * root_tau, curve[0].adev_sigma * root_tau, false};
  }

  // Bias instability: the floor min(sigma) = 0.664 B, seen only when the curve rises after it.
  fit.bias_instability = {curve[i_min].adev / kFlickerFloor,
                          curve[i_min].adev_sigma / kFlickerFloor, i_min + 1 < n};

  // Rate random walk, sigma = K sqrt(tau / 3), from the points beyond the minimum at slope +1/2
  // +- 0.25. The noise terms add in variance (IEEE 952 C.1), so the white term fitted above is
  // taken out of each point first: y = sqrt(adev^2 - N^2 / tau), sigma_y = adev sigma_adev / y.
  f.clear();
  y.clear();
  s.clear();
  const double white = fit.white_density.value;
  for (size_t j = i_min + 1; j < n; ++j) {
    if (!usable(j) || !(std::abs(slope[j] - kRandomWalkSlope) <= kRandomWalkSlopeTol)) continue;
    const double rest = curve[j].adev * curve[j].adev - white * white / curve[j].tau_s;
    if (rest <= 0.0) continue;
    f.push_back(std::sqrt(curve[j].tau_s / 3.0));
    y.push_back(std::sqrt(rest));
    s.push_back(curve[j].adev * curve[j].adev_sigma / y.back());
  }
  if (f.size() >= 2) fit.random_walk = FitProportional(f, y, s);
  return fit;
}

std::vector<RestSegment> FindRestSegments(const std::vector<ImuSample>& imu,
                                          double min_duration_s,
                                          double gyro_tol_rad_s,
                                          double accel_tol_m_s2) {
  if (imu.empty()) return {};
  const size_t n = imu.size();
  const auto block_ns = static_cast<TimeNs>(kRestSegmentBlockS * 1e9);
  const auto gap_ns = static_cast<TimeNs>(kRestSegmentMaxGapS * 1e9);

  // Blocks of kRestSegmentBlockS from their first sample; a gap (or a step back in time) ends a
  // block early and separates it from the next.
  struct Block {
    size_t begin, end;
    Eigen::Vector3d gyro_mean, accel_mean;
    bool after_gap;
  };
  std::vector<Block> blocks;
  bool gap_before = false;
  for (size_t i = 0; i < n;) {
    Block b{i, i, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), gap_before};
    gap_before = false;
    size_t j = i;
    while (true) {
      b.gyro_mean += imu[j].gyro_rad_s;
      b.accel_mean += imu[j].accel_m_s2;
      ++j;
      if (j == n) break;
      const TimeNs dt = imu[j].t_ns - imu[j - 1].t_ns;
      if (dt > gap_ns || dt < 0) {
        gap_before = true;
        break;
      }
      if (imu[j].t_ns - imu[i].t_ns >= block_ns) break;
    }
    b.end = j;
    b.gyro_mean /= static_cast<double>(j - i);
    b.accel_mean /= static_cast<double>(j - i);
    blocks.push_back(b);
    i = j;
  }

  const double interval_s = MedianIntervalS(imu, 0, n);
  const auto duration = [&](size_t begin, size_t end) {
    return NsToSeconds(imu[end - 1].t_ns - imu[begin].t_ns) + interval_s;
  };
  const auto within = [&](const Block& b, const Block& ref) {
    return (b.gyro_mean - ref.gyro_mean).cwiseAbs().maxCoeff() <= gyro_tol_rad_s &&
           (b.accel_mean - ref.accel_mean).cwiseAbs().maxCoeff() <= accel_tol_m_s2;
  };

  // The run from every block as far as it stays at rest. A block half-way into or out of a
  // motion starts a short run of its own: taking the longest runs first and then only those
  // that do not overlap them keeps it from cutting the rest beside it.
  std::vector<RestSegment> runs;
  for (size_t r = 0; r < blocks.size(); ++r) {
    size_t e = r + 1;
    while (e < blocks.size() && !blocks[e].after_gap && within(blocks[e], blocks[r])) ++e;
    RestSegment run{blocks[r].begin, blocks[e - 1].end, 0.0};
    run.duration_s = duration(run.begin, run.end);
    if (run.duration_s >= min_duration_s) runs.push_back(run);
  }
  std::stable_sort(runs.begin(), runs.end(), [](const RestSegment& a, const RestSegment& b) {
    return a.duration_s > b.duration_s;
  });
  std::vector<RestSegment> chosen;
  for (const RestSegment& run : runs) {
    const bool overlaps = std::any_of(chosen.begin(), chosen.end(), [&](const RestSegment& c) {
      return run.begin < c.end && c.begin < run.end;
    });
    if (!overlaps) chosen.push_back(run);
  }
  return chosen;
}

ImuAllanReport AnalyseImuAtRest(const std::vector<ImuSample>& imu, const RestSegment& rest) {
  if (rest.end > imu.size() || rest.begin >= rest.end || rest.end - rest.begin < 20) {
    throw std::invalid_argument("AnalyseImuAtRest: segment [" + std::to_string(rest.begin) + ", " +
                                std::to_string(rest.end) + ") of " + std::to_string(imu.size()) +
                                " samples: need 20 within");
  }
  const double interval_s = MedianIntervalS(imu, rest.begin, rest.end);
  if (interval_s <= 0.0) {
    throw std::invalid_argument("AnalyseImuAtRest: no positive sample interval in the segment");
  }
  ImuAllanReport report;
  report.rest = rest;
  report.rate_hz = 1.0 / interval_s;
  std::vector<double> x(rest.end - rest.begin);
  for (int axis = 0; axis < 3; ++axis) {
    for (size_t i = rest.begin; i < rest.end; ++i) x[i - rest.begin] = imu[i].gyro_rad_s[axis];
    report.gyro[axis] = OverlappingAllanDeviation(x, report.rate_hz);
    report.gyro_fit[axis] = FitAllan(report.gyro[axis]);
    for (size_t i = rest.begin; i < rest.end; ++i) x[i - rest.begin] = imu[i].accel_m_s2[axis];
    report.accel[axis] = OverlappingAllanDeviation(x, report.rate_hz);
    report.accel_fit[axis] = FitAllan(report.accel[axis]);
  }
  report.gyro_combined = Combine(report.gyro_fit);
  report.accel_combined = Combine(report.accel_fit);
  return report;
}

void WriteAllanCsv(const std::string& path, const ImuAllanReport& report) {
  AtomicFile file(path);  // throws InputError (a std::runtime_error) naming the path
  std::ofstream& out = file.stream();
  const char* kAxes = "xyz";
  out << "tau_s";
  for (const char* suffix : {"adev", "sigma"}) {
    for (const char* sensor : {"gyro", "accel"}) {
      for (int a = 0; a < 3; ++a) out << ',' << sensor << '_' << kAxes[a] << '_' << suffix;
    }
  }
  out << '\n';
  char buf[32];
  for (size_t i = 0; i < report.gyro[0].size(); ++i) {
    std::snprintf(buf, sizeof(buf), "%.9g", report.gyro[0][i].tau_s);
    out << buf;
    for (int kind = 0; kind < 2; ++kind) {
      for (const auto* sensor : {&report.gyro, &report.accel}) {
        for (int a = 0; a < 3; ++a) {
          out << ',';
          const std::vector<AllanPoint>& curve = (*sensor)[a];
          if (i >= curve.size()) continue;  // not for one segment: all curves share their taus
          std::snprintf(buf, sizeof(buf), "%.9g", kind == 0 ? curve[i].adev : curve[i].adev_sigma);
          out << buf;
        }
      }
    }
    out << '\n';
  }
  file.Commit();
}

namespace {

std::string XmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.2f", v);
  return buf;
}

std::string Sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3g", v);
  return buf;
}

/// One log-log panel: plot area at (x0, y0), w x h pixels, decades [lx0, lx1] x [ly0, ly1].
struct Panel {
  double x0, y0, w, h;
  int lx0, lx1, ly0, ly1;
  double X(double tau) const { return x0 + w * (std::log10(tau) - lx0) / (lx1 - lx0); }
  double Y(double v) const { return y0 + h * (1.0 - (std::log10(v) - ly0) / (ly1 - ly0)); }
};

constexpr const char* kAxisColour[3] = {"#d62728", "#2ca02c", "#1f77b4"};

void DrawPanel(std::ostream& out,
               int index,
               double x_left,
               const std::array<std::vector<AllanPoint>, 3>& curves,
               const std::array<AllanFit, 3>& fits,
               const std::string& sensor,
               const std::string& unit,
               const std::string& rw_unit) {
  // Ranges: whole decades around every positive value drawn.
  double t_lo = HUGE_VAL, t_hi = 0.0, v_lo = HUGE_VAL, v_hi = 0.0;
  for (const auto& c : curves) {
    for (const AllanPoint& p : c) {
      if (!Usable(p)) continue;
      t_lo = std::min(t_lo, p.tau_s);
      t_hi = std::max(t_hi, p.tau_s);
      v_lo = std::min(v_lo, p.adev - p.adev_sigma > 0.0 ? p.adev - p.adev_sigma : p.adev);
      v_hi = std::max(v_hi, p.adev + p.adev_sigma);
    }
  }
  if (!(t_hi > 0.0)) {  // nothing to draw: an empty decade
    t_lo = v_lo = 1.0;
    t_hi = v_hi = 10.0;
  }
  Panel p{x_left + 80.0, 50.0, 380.0, 330.0, 0, 0, 0, 0};
  p.lx0 = static_cast<int>(std::floor(std::log10(t_lo)));
  p.lx1 = std::max(p.lx0 + 1, static_cast<int>(std::ceil(std::log10(t_hi))));
  p.ly0 = static_cast<int>(std::floor(std::log10(v_lo)));
  p.ly1 = std::max(p.ly0 + 1, static_cast<int>(std::ceil(std::log10(v_hi))));

  const std::string clip = "clip" + std::to_string(index);
  out << "<clipPath id=\"" << clip << "\"><rect x=\"" << Num(p.x0) << "\" y=\"" << Num(p.y0)
      << "\" width=\"" << Num(p.w) << "\" height=\"" << Num(p.h) << "\"/></clipPath>\n";
  // Grid: decades solid, 2..9 faint; tick labels 10^k at the decades.
  for (int k = p.lx0; k <= p.lx1; ++k) {
    for (int s = 1; s <= (k < p.lx1 ? 9 : 1); ++s) {
      const double x = p.X(s * std::pow(10.0, k));
      out << "<line x1=\"" << Num(x) << "\" y1=\"" << Num(p.y0) << "\" x2=\"" << Num(x)
          << "\" y2=\"" << Num(p.y0 + p.h) << "\" stroke=\"" << (s == 1 ? "#bbb" : "#eee")
          << "\"/>\n";
    }
    out << "<text x=\"" << Num(p.X(std::pow(10.0, k))) << "\" y=\"" << Num(p.y0 + p.h + 18)
        << "\" text-anchor=\"middle\">10<tspan dy=\"-6\" font-size=\"9\">" << k
        << "</tspan></text>\n";
  }
  for (int k = p.ly0; k <= p.ly1; ++k) {
    for (int s = 1; s <= (k < p.ly1 ? 9 : 1); ++s) {
      const double y = p.Y(s * std::pow(10.0, k));
      out << "<line x1=\"" << Num(p.x0) << "\" y1=\"" << Num(y) << "\" x2=\"" << Num(p.x0 + p.w)
          << "\" y2=\"" << Num(y) << "\" stroke=\"" << (s == 1 ? "#bbb" : "#eee") << "\"/>\n";
    }
    out << "<text x=\"" << Num(p.x0 - 6) << "\" y=\"" << Num(p.Y(std::pow(10.0, k)) + 4)
        << "\" text-anchor=\"end\">10<tspan dy=\"-6\" font-size=\"9\">" << k << "</tspan></text>\n";
  }
  out << "<rect x=\"" << Num(p.x0) << "\" y=\"" << Num(p.y0) << "\" width=\"" << Num(p.w)
      << "\" height=\"" << Num(p.h) << "\" fill=\"none\" stroke=\"#000\"/>\n";
  out << "<text x=\"" << Num(p.x0 + p.w / 2) << "\" y=\"" << Num(p.y0 - 10)
      << "\" text-anchor=\"middle\" font-weight=\"bold\">" << XmlEscape(sensor) << "</text>\n";
  out << "<text x=\"" << Num(p.x0 + p.w / 2) << "\" y=\"" << Num(p.y0 + p.h + 38)
      << "\" text-anchor=\"middle\">averaging time τ [s]</text>\n";
  out << "<text transform=\"translate(" << Num(x_left + 22) << "," << Num(p.y0 + p.h / 2)
      << ") rotate(-90)\" text-anchor=\"middle\">Allan deviation [" << XmlEscape(unit)
      << "]</text>\n";

  out << "<g clip-path=\"url(#" << clip << ")\">\n";
  const double tau_a = std::pow(10.0, p.lx0), tau_b = std::pow(10.0, p.lx1);
  for (int a = 0; a < 3; ++a) {
    // 1-sigma band: adev +- sigma (the lower edge held above 0 for the log scale).
    std::string upper, lower;
    for (const AllanPoint& q : curves[a]) {
      if (!Usable(q)) continue;
      const double lo = std::max(q.adev - q.adev_sigma, std::pow(10.0, p.ly0 - 1));
      upper += Num(p.X(q.tau_s)) + "," + Num(p.Y(q.adev + q.adev_sigma)) + " ";
      lower = Num(p.X(q.tau_s)) + "," + Num(p.Y(lo)) + " " + lower;
    }
    out << "<polygon points=\"" << upper << lower << "\" fill=\"" << kAxisColour[a]
        << "\" fill-opacity=\"0.15\" stroke=\"none\"/>\n";
    out << "<polyline points=\"";
    for (const AllanPoint& q : curves[a]) {
      if (Usable(q)) out << Num(p.X(q.tau_s)) << "," << Num(p.Y(q.adev)) << " ";
    }
    out << "\" fill=\"none\" stroke=\"" << kAxisColour[a] << "\" stroke-width=\"1.5\"/>\n";
    // Fitted lines are straight in log-log: two points span the panel.
    const double n_d = fits[a].white_density.value;
    if (n_d > 0.0) {
      out << "<line x1=\"" << Num(p.X(tau_a)) << "\" y1=\"" << Num(p.Y(n_d / std::sqrt(tau_a)))
          << "\" x2=\"" << Num(p.X(tau_b)) << "\" y2=\"" << Num(p.Y(n_d / std::sqrt(tau_b)))
          << "\" stroke=\"" << kAxisColour[a] << "\" stroke-dasharray=\"6,4\"/>\n";
    }
    const double k_d = fits[a].random_walk.value;
    if (fits[a].random_walk.identified && k_d > 0.0) {
      out << "<line x1=\"" << Num(p.X(tau_a)) << "\" y1=\""
          << Num(p.Y(k_d * std::sqrt(tau_a / 3.0))) << "\" x2=\"" << Num(p.X(tau_b)) << "\" y2=\""
          << Num(p.Y(k_d * std::sqrt(tau_b / 3.0))) << "\" stroke=\"" << kAxisColour[a]
          << "\" stroke-dasharray=\"2,3\"/>\n";
    }
  }
  out << "</g>\n";

  // Legend under the panel: one line per axis with its fitted terms.
  double y = p.y0 + p.h + 60;
  for (int a = 0; a < 3; ++a, y += 16) {
    const AllanFit& f = fits[a];
    out << "<line x1=\"" << Num(p.x0) << "\" y1=\"" << Num(y - 4) << "\" x2=\"" << Num(p.x0 + 20)
        << "\" y2=\"" << Num(y - 4) << "\" stroke=\"" << kAxisColour[a]
        << "\" stroke-width=\"1.5\"/>\n";
    out << "<text x=\"" << Num(p.x0 + 26) << "\" y=\"" << Num(y) << "\">"
        << "xyz"[a] << ": N " << Sci(f.white_density.value)
        << (f.white_density.identified ? "" : "?") << ", B " << Sci(f.bias_instability.value)
        << (f.bias_instability.identified ? "" : "?") << ", K "
        << (f.random_walk.identified ? Sci(f.random_walk.value) : std::string("-")) << "</text>\n";
  }
  out << "<line x1=\"" << Num(p.x0) << "\" y1=\"" << Num(y - 4) << "\" x2=\"" << Num(p.x0 + 20)
      << "\" y2=\"" << Num(y - 4) << "\" stroke=\"#555\" stroke-dasharray=\"6,4\"/>\n";
  out << "<text x=\"" << Num(p.x0 + 26) << "\" y=\"" << Num(y) << "\">N/√τ, N in "
      << XmlEscape(unit) << "/√Hz</text>\n";
  out << "<line x1=\"" << Num(p.x0 + 200) << "\" y1=\"" << Num(y - 4) << "\" x2=\""
      << Num(p.x0 + 220) << "\" y2=\"" << Num(y - 4)
      << "\" stroke=\"#555\" stroke-dasharray=\"2,3\"/>\n";
  out << "<text x=\"" << Num(p.x0 + 226) << "\" y=\"" << Num(y) << "\">K√(τ/3), K in "
      << XmlEscape(rw_unit) << "</text>\n";
  y += 16;
  out << "<text x=\"" << Num(p.x0) << "\" y=\"" << Num(y)
      << "\" fill=\"#555\">B: bias instability, min/0.664; ? not identified; band: 1σ</text>\n";
}

}  // namespace

void WriteAllanSvg(const std::string& path,
                   const ImuAllanReport& report,
                   const std::string& title) {
  AtomicFile file(path);  // throws InputError (a std::runtime_error) naming the path
  std::ofstream& out = file.stream();
  const double width = 1000, height = 540;
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" viewBox=\"0 0 " << width << " " << height
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n"
      << "<text x=\"" << width / 2 << "\" y=\"20\" text-anchor=\"middle\" font-size=\"15\">"
      << XmlEscape(title) << " — rest " << Num(report.rest.duration_s) << " s at "
      << Num(report.rate_hz) << " Hz</text>\n";
  DrawPanel(out, 0, 0.0, report.gyro, report.gyro_fit, "gyroscope", "rad/s", "rad/s²/√Hz");
  DrawPanel(out, 1, 500.0, report.accel, report.accel_fit, "accelerometer", "m/s²", "m/s³/√Hz");
  out << "</svg>\n";
  file.Commit();
}

}  // namespace skerry
