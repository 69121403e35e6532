#pragma once
/// \file
/// A constant (double) matrix times a vector of T, for autodiff functors. `A.cast<T>() * x` with
/// T = ceres::Jet multiplies Jet by Jet (value and every derivative of both sides, although A's
/// derivatives are zero); this multiplies double by Jet, about half the work, and skips the
/// zeros of a triangular A when told to.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>

namespace skerry {

template <typename T, int R, int C, typename Derived>
Eigen::Matrix<T, R, 1> ConstantTimes(const Eigen::Matrix<double, R, C>& A,
                                     const Eigen::MatrixBase<Derived>& x,
                                     bool lower_triangular = false) {
  Eigen::Matrix<T, R, 1> out;
  for (int i = 0; i < R; ++i) {
    T sum = T(0);
    const int j_end = lower_triangular ? std::min(i + 1, C) : C;
    for (int j = 0; j < j_end; ++j) sum += A(i, j) * x(j);
    out(i) = sum;
  }
  return out;
}

/// Hamilton products with one constant factor, written as the 4x4 matrix of the constant acting
/// on the other's coefficients (Eigen order x, y, z, w): double times T, not T times T.
template <typename T>
Eigen::Quaternion<T> ConstantTimes(const Eigen::Quaterniond& a, const Eigen::Quaternion<T>& b) {
  Eigen::Matrix4d L;                 // coeffs(a b) = L(a) coeffs(b)
  L << a.w(), -a.z(), a.y(), a.x(),  //
      a.z(), a.w(), -a.x(), a.y(),   //
      -a.y(), a.x(), a.w(), a.z(),   //
      -a.x(), -a.y(), -a.z(), a.w();
  return Eigen::Quaternion<T>(ConstantTimes<T>(L, b.coeffs()));
}

template <typename T>
Eigen::Quaternion<T> TimesConstant(const Eigen::Quaternion<T>& a, const Eigen::Quaterniond& b) {
  Eigen::Matrix4d R;                 // coeffs(a b) = R(b) coeffs(a)
  R << b.w(), b.z(), -b.y(), b.x(),  //
      -b.z(), b.w(), b.x(), b.y(),   //
      b.y(), -b.x(), b.w(), b.z(),   //
      -b.x(), -b.y(), -b.z(), b.w();
  return Eigen::Quaternion<T>(ConstantTimes<T>(R, a.coeffs()));
}

}  // namespace skerry
