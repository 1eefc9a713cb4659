#include "clutterscope/estimator/fit_information.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace clutterscope::estimator {

double depth_variance(const PixelNoise& noise, double z_m) {
  const double sigma = noise.a_m + noise.b_per_m * (z_m - noise.z0_m) * (z_m - noise.z0_m);
  const double disparity_step = noise.disparity_step_per_m * z_m * z_m;
  return sigma * sigma + (noise.quantisation_m * noise.quantisation_m) / 12.0 +
         disparity_step * disparity_step / 12.0;
}

double matching_window_pixels(double window_half_px, double lateral_scale) {
  const double side = 2.0 * window_half_px * lateral_scale;
  return std::max(1.0, side * side);
}

double robust_variance(std::vector<double> residuals) {
  if (residuals.empty()) return 0;
  const auto median_of = [](std::vector<double>& values) {
    const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    return *middle;
  };
  const double median = median_of(residuals);
  for (double& r : residuals) r = std::abs(r - median);
  const double mad = 1.4826 * median_of(residuals);
  return mad * mad;
}

double correlated_pixels_from_residuals(const std::vector<double>& residuals, int width,
                                        int height) {
  if (width <= 0 || height <= 0 || residuals.size() != static_cast<std::size_t>(width) * height)
    throw std::invalid_argument("residual image size does not match its width and height");
  double sum = 0, squares = 0;
  long count = 0;
  for (const double r : residuals) {
    if (std::isnan(r)) continue;
    sum += r;
    squares += r * r;
    ++count;
  }
  if (count < 2) return 1;
  const double mean = sum / count;
  const double variance = squares / count - mean * mean;
  if (!(variance > 0)) return 1;
  // Lag-1 correlation along one image axis (du, dv) over the pairs with both residuals.
  const auto lag_correlation = [&](int du, int dv, long* pairs) {
    double products = 0;
    *pairs = 0;
    for (int v = 0; v + dv < height; ++v)
      for (int u = 0; u + du < width; ++u) {
        const double a = residuals[static_cast<std::size_t>(v) * width + u];
        const double b = residuals[static_cast<std::size_t>(v + dv) * width + u + du];
        if (std::isnan(a) || std::isnan(b)) continue;
        products += (a - mean) * (b - mean);
        ++*pairs;
      }
    return *pairs > 0 ? std::clamp(products / (*pairs * variance), 0.0, 0.999) : 0.0;
  };
  long pairs_u = 0, pairs_v = 0;
  const double rho_u = lag_correlation(1, 0, &pairs_u);
  const double rho_v = lag_correlation(0, 1, &pairs_v);
  if (pairs_u + pairs_v < 2) return 1;
  const double c = (1 + rho_u) / (1 - rho_u) * (1 + rho_v) / (1 - rho_v);
  return std::clamp(c, 1.0, static_cast<double>(count));
}

Eigen::Matrix3d pixel_information(const Eigen::Matrix3d& normal_sum, int pixels,
                                  double noise_variance, double correlated_pixels,
                                  double excess_variance, double bias_variance) {
  if (!(noise_variance > 0) || !std::isfinite(noise_variance))
    throw std::invalid_argument("pixel noise variance must be finite and > 0");
  if (!(correlated_pixels >= 1) || !std::isfinite(correlated_pixels))
    throw std::invalid_argument("correlated pixels must be finite and >= 1");
  if (!(excess_variance >= 0) || !std::isfinite(excess_variance))
    throw std::invalid_argument("excess residual variance must be finite and >= 0");
  if (!(bias_variance >= 0) || !std::isfinite(bias_variance))
    throw std::invalid_argument("normal-weighted bias variance must be finite and >= 0");
  if (pixels <= 0) return Eigen::Matrix3d::Zero();
  const double n = pixels;
  const double per_pixel = correlated_pixels * noise_variance + n * excess_variance;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> mean_normals(
      0.5 * (normal_sum + normal_sum.transpose()) / n);
  const Eigen::Vector3d information = mean_normals.eigenvalues().unaryExpr(
      [&](double m) { return m > 0 ? n * m * m / (per_pixel * m + n * bias_variance) : 0.0; });
  const Eigen::Matrix3d& u = mean_normals.eigenvectors();
  const Eigen::Matrix3d j = u * information.asDiagonal() * u.transpose();
  return 0.5 * (j + j.transpose());
}

Eigen::Matrix3d belief_bound(const GaussianMixture& belief) {
  if (belief.dimension() != 3 || belief.size() < 1)
    throw std::invalid_argument("belief bound needs a 3-D mixture with components");
  const Eigen::Matrix3d weighted = mixture_covariance(belief);
  const Eigen::Vector3d centre = belief.means.rowwise().mean();
  const Eigen::Matrix3Xd offsets = belief.means.colwise() - centre;
  const Eigen::Matrix3d spread = offsets * offsets.transpose() / static_cast<double>(belief.size());
  const double ess = std::max(1.0, effective_sample_size(belief.weights));
  return weighted + spread / ess;
}

Eigen::Matrix3d other_fits_spread(const Eigen::Vector3d& estimate,
                                  const std::vector<Eigen::Vector3d>& others) {
  if (!estimate.allFinite()) throw std::invalid_argument("other fits: the estimate is not finite");
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& fit : others) {
    if (!fit.allFinite()) throw std::invalid_argument("other fits: a fit is not finite");
    spread += (fit - estimate) * (fit - estimate).transpose();
  }
  return spread / static_cast<double>(1 + others.size());
}

namespace {

// B = L L^T and the eigen decomposition of L^T J L (the fit's information, belief-whitened).
struct Whitened {
  Eigen::Matrix3d l, u;
  Eigen::Vector3d information;
};

// L of a covariance's symmetric part, L L^T; throws std::invalid_argument naming `what` for one
// that is not positive definite.
Eigen::Matrix3d cholesky_factor(const Eigen::Matrix3d& covariance, const std::string& what) {
  const Eigen::Matrix3d symmetric = 0.5 * (covariance + covariance.transpose());
  const Eigen::LLT<Eigen::Matrix3d> cholesky(symmetric);
  if (!symmetric.allFinite() || cholesky.info() != Eigen::Success)
    throw std::invalid_argument(what + " is not positive definite");
  return cholesky.matrixL();
}

Whitened whiten(const Eigen::Matrix3d& belief_covariance, const Eigen::Matrix3d& fit_information) {
  Whitened w;
  w.l = cholesky_factor(belief_covariance, "belief covariance");
  if (!fit_information.allFinite()) throw std::invalid_argument("fit information is not finite");
  const Eigen::Matrix3d j = 0.5 * (fit_information + fit_information.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(w.l.transpose() * j * w.l);
  w.u = eigen.eigenvectors();
  w.information = eigen.eigenvalues();
  return w;
}

}  // namespace

Eigen::Matrix3d information_maximum(const Eigen::Matrix3d& belief_covariance,
                                    const Eigen::Matrix3d& fit_information) {
  const Whitened w = whiten(belief_covariance, fit_information);
  const Eigen::Vector3d variances =
      w.information.unaryExpr([](double v) { return 1.0 / std::max(v, 1.0); });
  const Eigen::Matrix3d covariance =
      w.l * w.u * variances.asDiagonal() * w.u.transpose() * w.l.transpose();
  return 0.5 * (covariance + covariance.transpose());
}

Eigen::Matrix3d covariance_maximum(const Eigen::Matrix3d& a, const Eigen::Matrix3d& c) {
  const Eigen::Matrix3d l = cholesky_factor(a, "covariance maximum: the first covariance");
  if (!c.allFinite()) throw std::invalid_argument("covariance maximum: the second is not finite");
  const Eigen::Matrix3d l_inverse = l.inverse();
  const Eigen::Matrix3d whitened = l_inverse * c * l_inverse.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(0.5 *
                                                             (whitened + whitened.transpose()));
  const Eigen::Vector3d larger = eigen.eigenvalues().cwiseMax(1.0);
  const Eigen::Matrix3d& u = eigen.eigenvectors();
  const Eigen::Matrix3d covariance = l * u * larger.asDiagonal() * u.transpose() * l.transpose();
  return 0.5 * (covariance + covariance.transpose());
}

Eigen::Vector3d information_maximum_mean(const Eigen::Vector3d& belief_mean,
                                         const Eigen::Matrix3d& belief_covariance,
                                         const Eigen::Vector3d& fit_mean,
                                         const Eigen::Matrix3d& fit_information) {
  const Whitened w = whiten(belief_covariance, fit_information);
  const Eigen::Vector3d belief =
      w.u.transpose() * w.l.triangularView<Eigen::Lower>().solve(belief_mean);
  const Eigen::Vector3d fit = w.u.transpose() * w.l.triangularView<Eigen::Lower>().solve(fit_mean);
  Eigen::Vector3d chosen;
  for (int i = 0; i < 3; ++i) chosen[i] = w.information[i] >= 1.0 ? fit[i] : belief[i];
  return w.l * w.u * chosen;
}

}  // namespace clutterscope::estimator
