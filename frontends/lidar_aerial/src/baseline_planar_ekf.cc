#include "skerry/lidar_aerial/baseline_planar_ekf.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>

namespace skerry::lidar_aerial::baseline {

PlanarEkf::PlanarEkf(const PlanarEstimate& start, const PlanarEkfOptions& options)
    : est_(start), options_(options) {
  if (!(options.rate_hz > 0.0)) throw std::invalid_argument("PlanarEkf: rate_hz must be > 0");
}

void PlanarEkf::Predict(TimeNs t_ns, double yaw_rate) {
  if (t_ns < est_.t_ns) throw std::invalid_argument("PlanarEkf: time goes back");
  const double step = 1.0 / options_.rate_hz;
  const double deg = M_PI / 180.0;
  while (est_.t_ns < t_ns) {
    const double dt = std::min(step, NsToSeconds(t_ns - est_.t_ns));
    Eigen::Matrix<double, 5, 1>& x = est_.x;
    const double c = std::cos(x(4)), s = std::sin(x(4));
    const double u = x(2), w = x(3);
    // x' = x + R(psi) [u, w] dt, psi' = psi + r dt; velocities constant.
    Eigen::Matrix<double, 5, 5> F = Eigen::Matrix<double, 5, 5>::Identity();
    F(0, 2) = c * dt;
    F(0, 3) = -s * dt;
    F(0, 4) = (-s * u - c * w) * dt;
    F(1, 2) = s * dt;
    F(1, 3) = c * dt;
    F(1, 4) = (c * u - s * w) * dt;
    x(0) += (c * u - s * w) * dt;
    x(1) += (s * u + c * w) * dt;
    x(4) = WrapAngle(x(4) + yaw_rate * dt);
    Eigen::Matrix<double, 5, 1> q;
    q << options_.q_position, options_.q_position, options_.q_velocity, options_.q_velocity,
        options_.q_heading_deg2 * deg * deg;
    est_.P = F * est_.P * F.transpose();
    est_.P.diagonal() += options_.alpha1 * q * dt;
    est_.t_ns += SecondsToNs(dt);
    if (t_ns - est_.t_ns < 1000) est_.t_ns = t_ns;  // no sub-microsecond remainder
  }
}

void PlanarEkf::Update(const Eigen::MatrixXd& H,
                       const Eigen::VectorXd& innovation,
                       const Eigen::MatrixXd& R) {
  const Eigen::MatrixXd S = H * est_.P * H.transpose() + R;
  const Eigen::MatrixXd K =
      est_.P * H.transpose() * S.ldlt().solve(Eigen::MatrixXd::Identity(S.rows(), S.cols()));
  est_.x += K * innovation;
  est_.x(4) = WrapAngle(est_.x(4));
  // Joseph form: stays symmetric positive definite.
  const Eigen::Matrix<double, 5, 5> I_KH = Eigen::Matrix<double, 5, 5>::Identity() - K * H;
  est_.P = I_KH * est_.P * I_KH.transpose() + K * R * K.transpose();
}

void PlanarEkf::UpdatePosition(const Eigen::Vector2d& p, bool loss) {
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2, 5);
  H(0, 0) = H(1, 1) = 1.0;
  const double a = loss ? options_.alpha2_loss : options_.alpha2;
  Update(H, p - est_.x.head<2>(), a * Eigen::MatrixXd::Identity(2, 2));
}

void PlanarEkf::UpdatePose(const PlanarPose& pose) {
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, 5);
  H(0, 0) = H(1, 1) = H(2, 4) = 1.0;
  Eigen::VectorXd innovation(3);
  innovation << pose.t - est_.x.head<2>(), WrapAngle(pose.yaw - est_.x(4));
  const double deg = M_PI / 180.0;
  const Eigen::Vector3d r(1.0, 1.0, deg * deg);
  Update(H, innovation, options_.alpha3 * Eigen::MatrixXd(r.asDiagonal()));
}

}  // namespace skerry::lidar_aerial::baseline
