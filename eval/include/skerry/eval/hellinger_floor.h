#pragma once
/// \file
/// The Hellinger distance two runs show when nothing differs but their noise: the floor under
/// any AHED (docs/fidelity.md, *The floor*).
///
/// Two independent noise realisations of the same truth through one consistent estimator give,
/// per epoch and per k-dimensional block, two Gaussians N(x1, S) and N(x2, S) whose means each
/// scatter about the truth with S: their difference d = x2 - x1 ~ N(0, 2 S). With P1 = P2 = S the
/// Bhattacharyya distance is D_B = d' S^-1 d / 8 = q / 4 with q = d' (2 S)^-1 d ~ chi2_k, so
///
///   HED^2 = 1 - exp(-q / 4),   E[HED^2] = 1 - (1 + 2/4)^(-k/2) = 1 - 1.5^(-k/2)
///
/// (the chi-square moment generating function E[exp(t q)] = (1 - 2t)^(-k/2) at t = -1/4), and
/// E[HED] = E[sqrt(1 - exp(-q/4))], by quadrature over the chi-square density. A twin that is
/// perfect, a configuration that is the same, scores about this, not zero: 0.36 for a 1-D block,
/// 0.65 for 3-D, 0.73 for 4-D, 0.83 for 6-D.

namespace skerry {

struct HellingerFloor {
  int dimension = 0;
  double mean_hed = 0.0;   ///< E[HED]
  double mean_hed2 = 0.0;  ///< E[HED^2] = 1 - 1.5^(-k/2)
  double sd_hed = 0.0;     ///< the standard deviation of one epoch's HED
};

/// The floor for a block of `dimension` >= 1 (std::invalid_argument otherwise).
HellingerFloor ConsistentRunsHellingerFloor(int dimension);

}  // namespace skerry
