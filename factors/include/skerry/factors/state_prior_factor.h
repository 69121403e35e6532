#pragma once
/// \file
/// Gaussian prior on a full navigation state (used on the first keyframe):
///   r = sqrt_info * [ Log(q q0^-1) ; p - p0 ; v - v0 ; bg - bg0 ; ba - ba0 ]
/// The rotation error is the world-frame (left) rotation vector, matching the 15-D tangent order
/// of nav_state.h. Parameter blocks: q_w_b[4], p_w_b[3], v_w[3], bg[3], ba[3].

#include <ceres/autodiff_cost_function.h>

#include <memory>

#include "skerry/core/nav_state.h"
#include "skerry/core/so3.h"

namespace skerry {

class StatePriorFactor {
 public:
  StatePriorFactor(const NavState& prior, const StateCovariance& covariance);

  template <typename T>
  bool operator()(const T* q_ptr,
                  const T* p_ptr,
                  const T* v_ptr,
                  const T* bg_ptr,
                  const T* ba_ptr,
                  T* residual_ptr) const {
    using Vec3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_ptr);
    Eigen::Matrix<T, 15, 1> e;
    e.template segment<3>(kRot) = LogQ<T>(q * prior_.q_w_b.conjugate().cast<T>());
    e.template segment<3>(kPos) = Eigen::Map<const Vec3>(p_ptr) - prior_.p_w_b.cast<T>();
    e.template segment<3>(kVel) = Eigen::Map<const Vec3>(v_ptr) - prior_.v_w.cast<T>();
    e.template segment<3>(kBg) = Eigen::Map<const Vec3>(bg_ptr) - prior_.bg.cast<T>();
    e.template segment<3>(kBa) = Eigen::Map<const Vec3>(ba_ptr) - prior_.ba.cast<T>();
    Eigen::Map<Eigen::Matrix<T, 15, 1>> r(residual_ptr);
    r = sqrt_info_.cast<T>() * e;
    return true;
  }

  static std::unique_ptr<ceres::CostFunction> Create(const NavState& prior,
                                                     const StateCovariance& covariance);

 private:
  NavState prior_;
  StateCovariance sqrt_info_;
};

}  // namespace skerry
