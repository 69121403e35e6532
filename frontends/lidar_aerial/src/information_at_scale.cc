#include "skerry/lidar_aerial/information_at_scale.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace skerry::lidar_aerial {
namespace {

// f = |r|^2 at (q, p, v), with the Jacobian on p (row-major, n x 3) when `jp` is given; -1 when
// it cannot be evaluated.
double SquaredNorm(const ceres::CostFunction& cost,
                   const NavState& s,
                   const Eigen::Vector3d& p,
                   std::vector<double>* r,
                   std::vector<double>* jp) {
  const double* values[] = {s.q_w_b.coeffs().data(), p.data(), s.v_w.data()};
  double* jacobians[] = {nullptr, jp ? jp->data() : nullptr, nullptr};
  if (!cost.Evaluate(values, r->data(), jp ? jacobians : nullptr)) return -1.0;
  const double f =
      Eigen::Map<const Eigen::VectorXd>(r->data(), static_cast<Eigen::Index>(r->size()))
          .squaredNorm();
  return std::isfinite(f) ? f : -1.0;
}

// The block seen at p0 + P (p - p0) (KeepAlong).
class KeptAlongCost : public ceres::CostFunction {
 public:
  KeptAlongCost(std::shared_ptr<ceres::CostFunction> inner,
                const Eigen::Vector3d& p0,
                const Eigen::Matrix3d& P)
      : inner_(std::move(inner)), p0_(p0), P_(P) {
    set_num_residuals(inner_->num_residuals());
    *mutable_parameter_block_sizes() = inner_->parameter_block_sizes();
  }

  bool Evaluate(double const* const* parameters,
                double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Eigen::Vector3d> p(parameters[1]);
    const Eigen::Vector3d mapped = p0_ + P_ * (p - p0_);
    // Blocks after (q, p, v), a calibrated mounting's, pass through unchanged.
    const size_t blocks = parameter_block_sizes().size();
    std::vector<const double*> inner_parameters(parameters, parameters + blocks);
    inner_parameters[1] = mapped.data();
    if (jacobians == nullptr || jacobians[1] == nullptr) {
      return inner_->Evaluate(inner_parameters.data(), residuals, jacobians);
    }
    // d r / d p = (d r / d mapped) P.
    const int n = num_residuals();
    std::vector<double> jp(static_cast<size_t>(n) * 3);
    std::vector<double*> inner_jacobians(jacobians, jacobians + blocks);
    inner_jacobians[1] = jp.data();
    if (!inner_->Evaluate(inner_parameters.data(), residuals, inner_jacobians.data())) return false;
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
    Eigen::Map<RowMajor>(jacobians[1], n, 3) = Eigen::Map<const RowMajor>(jp.data(), n, 3) * P_;
    return true;
  }

 private:
  std::shared_ptr<ceres::CostFunction> inner_;
  Eigen::Vector3d p0_;
  Eigen::Matrix3d P_;
};

}  // namespace

std::optional<WeakDirection> MeasureWeakDirection(const ceres::CostFunction& cost,
                                                  const NavState& at,
                                                  double scale_m) {
  const int n = cost.num_residuals();
  std::vector<double> r(static_cast<size_t>(n)), jp(static_cast<size_t>(n) * 3);
  const double f0 = SquaredNorm(cost, at, at.p_w_b, &r, &jp);
  if (f0 < 0.0) return std::nullopt;
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> J(jp.data(), n,
                                                                                      3);
  const Eigen::Matrix2d info = J.leftCols<2>().transpose() * J.leftCols<2>();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(info);
  const double lmax = eig.eigenvalues()(1);
  if (!(lmax > 0.0) || !std::isfinite(lmax)) return std::nullopt;
  WeakDirection out;
  out.direction = eig.eigenvectors().col(0);
  out.local = std::max(0.0, eig.eigenvalues()(0));
  out.at_scale = out.local;
  if (scale_m > 0.0 && out.local > 0.0) {
    const Eigen::Vector3d d(scale_m * out.direction.x(), scale_m * out.direction.y(), 0.0);
    const double fp = SquaredNorm(cost, at, at.p_w_b + d, &r, nullptr);
    const double fm = SquaredNorm(cost, at, at.p_w_b - d, &r, nullptr);
    // Off the map (not evaluable) one way: the other side alone.
    if (fp >= 0.0 && fm >= 0.0) {
      out.at_scale = (fp + fm - 2.0 * f0) / (2.0 * scale_m * scale_m);
    } else if (fp >= 0.0 || fm >= 0.0) {
      out.at_scale = (std::max(fp, fm) - f0) / (scale_m * scale_m);
    }
  }
  out.keep = out.local > 0.0 ? std::clamp(out.at_scale / out.local, 0.0, 1.0) : 1.0;
  out.constraint_ratio = out.keep * out.local / lmax;
  return out;
}

std::shared_ptr<ceres::CostFunction> KeepAlong(std::shared_ptr<ceres::CostFunction> cost,
                                               const Eigen::Vector3d& p0,
                                               const Eigen::Vector2d& w,
                                               double keep) {
  if (!(keep < 1.0)) return cost;
  const Eigen::Vector3d w3(w.x(), w.y(), 0.0);
  const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - (1.0 - std::sqrt(std::max(0.0, keep))) *
                                                              w3 * w3.transpose() /
                                                              w3.squaredNorm();
  return std::make_shared<KeptAlongCost>(std::move(cost), p0, P);
}

}  // namespace skerry::lidar_aerial
