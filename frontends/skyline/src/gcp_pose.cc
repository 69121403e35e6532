#include "skerry/skyline/gcp_pose.h"

#include <ceres/ceres.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "skerry/core/input_error.h"

namespace skerry::skyline {
namespace {

// "1951+9" -> 1960; a plain number as it is.
bool ParseSum(const std::string& text, double* value) {
  double sum = 0.0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t used = 0;
    double term = 0.0;
    try {
      term = std::stod(text.substr(pos), &used);
    } catch (const std::exception&) {
      return false;
    }
    sum += term;
    pos += used;
    if (pos < text.size()) {
      if (text[pos] != '+') return false;
      ++pos;
      if (pos == text.size()) return false;
    }
  }
  if (text.empty() || !std::isfinite(sum)) return false;
  *value = sum;
  return true;
}

struct GcpResidual {
  GcpResidual(const CameraModel& camera, const Eigen::Vector3d& d_w, const Eigen::Vector2d& px)
      : camera(camera), d_w(d_w), px(px) {}
  template <typename T>
  bool operator()(const T* q, const T* f, const T* k, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_c(q);
    const Eigen::Matrix<T, 3, 1> d_c = q_w_c.conjugate() * d_w.cast<T>();
    if (d_c.z() <= T(0)) return false;
    // Pinhole about the image centre with one radial term (k1): the photo's own lens.
    const T x = d_c.x() / d_c.z(), y = d_c.y() / d_c.z();
    const T radial = T(1) + k[0] * (x * x + y * y);
    r[0] = f[0] * x * radial + T(camera.cx()) - T(px.x());
    r[1] = f[0] * y * radial + T(camera.cy()) - T(px.y());
    return true;
  }
  const CameraModel& camera;
  Eigen::Vector3d d_w;
  Eigen::Vector2d px;
};

}  // namespace

std::vector<GcpRow> ReadGcpFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "(file)", "cannot open");
  std::vector<GcpRow> rows;
  std::string line;
  int n = 0;
  const char* names[] = {"X", "Y", "Z", "u", "v"};
  while (std::getline(in, line)) {
    ++n;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '%' || line[first] == '#') continue;
    std::istringstream s(line);
    std::vector<std::string> fields;
    std::string f;
    while (s >> f) fields.push_back(f);
    if (fields.size() != 5) {
      throw InputError(path, n, "(row)",
                       "expected 5 values X Y Z u v, found " + std::to_string(fields.size()));
    }
    double v[5];
    for (int i = 0; i < 5; ++i) {
      if (!ParseSum(fields[i], &v[i])) {
        throw InputError(path, n, names[i], "not a finite number: '" + fields[i] + "'");
      }
    }
    rows.push_back({Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector2d(v[3], v[4]), n});
  }
  if (rows.empty()) throw InputError(path, 0, "(file)", "no control points");
  return rows;
}

CameraRotationFit FitCameraRotation(const CameraModel& camera,
                                    const Eigen::Vector3d& p_w_c,
                                    const std::vector<Eigen::Vector3d>& points_w,
                                    const std::vector<Eigen::Vector2d>& pixels,
                                    const Eigen::Quaterniond& start,
                                    bool fit_focal,
                                    bool fit_k1) {
  CameraRotationFit fit;
  Eigen::Quaterniond q = start.normalized();
  double f = camera.fx();
  double k1 = 0.0;
  ceres::Problem problem;
  for (size_t i = 0; i < points_w.size(); ++i) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<GcpResidual, 2, 4, 1, 1>(
                                 new GcpResidual(camera, points_w[i] - p_w_c, pixels[i])),
                             nullptr, q.coeffs().data(), &f, &k1);
  }
  problem.SetManifold(q.coeffs().data(), new ceres::EigenQuaternionManifold);
  if (!fit_focal) problem.SetParameterBlockConstant(&f);
  if (!fit_k1) problem.SetParameterBlockConstant(&k1);
  ceres::Solver::Options options;
  options.max_num_iterations = 100;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  fit.q_w_c = q;
  fit.focal_px = f;
  fit.k1 = k1;
  fit.converged = summary.termination_type == ceres::CONVERGENCE;
  fit.rms_px = std::sqrt(2.0 * summary.final_cost / std::max<size_t>(1, points_w.size()));
  return fit;
}

}  // namespace skerry::skyline
