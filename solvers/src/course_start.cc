#include "skerry/solvers/course_start.h"

#include <cmath>
#include <complex>
#include <stdexcept>

namespace skerry {
namespace {

// Counter-clockwise turn from rates' cumulative trapezoid integral, linearly interpolated.
class Turn {
 public:
  explicit Turn(const std::vector<YawRate>& rates) : rates_(rates) {
    cumulative_.reserve(rates.size());
    double sum = 0.0;
    for (size_t k = 0; k < rates.size(); ++k) {
      if (k > 0) {
        sum += 0.5 * (rates[k - 1].rad_s + rates[k].rad_s) *
               NsToSeconds(rates[k].t_ns - rates[k - 1].t_ns);
      }
      cumulative_.push_back(sum);
    }
  }
  double At(TimeNs t_ns) const {
    if (rates_.empty() || t_ns <= rates_.front().t_ns) return 0.0;
    if (t_ns >= rates_.back().t_ns) return cumulative_.back();
    size_t lo = 0, hi = rates_.size() - 1;
    while (hi - lo > 1) {
      const size_t mid = (lo + hi) / 2;
      (rates_[mid].t_ns <= t_ns ? lo : hi) = mid;
    }
    const double u =
        NsToSeconds(t_ns - rates_[lo].t_ns) / NsToSeconds(rates_[hi].t_ns - rates_[lo].t_ns);
    return cumulative_[lo] + u * (cumulative_[hi] - cumulative_[lo]);
  }

 private:
  const std::vector<YawRate>& rates_;
  std::vector<double> cumulative_;
};

}  // namespace

CourseStart CourseAtFirstFix(const std::vector<CourseFix>& fixes,
                             const std::vector<YawRate>& rates,
                             double sigma_horizontal_m,
                             double gyro_bias_sigma_rad_s) {
  if (fixes.size() < 2) throw std::invalid_argument("CourseAtFirstFix: fewer than two fixes");
  const Turn turn(rates);
  const double turn0 = turn.At(fixes.front().t_ns);
  // Clockwise-from-north angles as complex arguments: z = dN + i dE. A counter-clockwise turn
  // dpsi lowers the heading, so a displacement made after it is rotated back by +dpsi.
  std::complex<double> sum(0.0, 0.0);
  for (size_t k = 0; k + 1 < fixes.size(); ++k) {
    const Eigen::Vector2d d = fixes[k + 1].en_m - fixes[k].en_m;
    const TimeNs t_mid = fixes[k].t_ns + (fixes[k + 1].t_ns - fixes[k].t_ns) / 2;
    sum += std::complex<double>(d.y(), d.x()) * std::polar(1.0, turn.At(t_mid) - turn0);
  }
  const double duration_s = NsToSeconds(fixes.back().t_ns - fixes.front().t_ns);
  const double length_m = std::abs(sum);
  CourseStart c;
  c.heading_rad = std::arg(sum);
  c.speed_m_s = duration_s > 0.0 ? length_m / duration_s : 0.0;
  // The end fixes' noise across the straightened length; a gyro bias b turns displacement k by
  // b t_k, on average b T/2.
  const double noise = length_m > 0.0 ? std::sqrt(2.0) * sigma_horizontal_m / length_m : M_PI;
  const double gyro = gyro_bias_sigma_rad_s * 0.5 * duration_s;
  c.sigma_rad = std::min(M_PI, std::hypot(noise, gyro));
  c.turned_rad = turn.At(fixes.back().t_ns) - turn0;
  return c;
}

}  // namespace skerry
