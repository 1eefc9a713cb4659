#pragma once

// What a translation fit of depth pixels knows about an object's position (issue 25, items 2
// and 5): the information of the point-to-plane residuals of every valid pixel, with the
// noise of the sensor that produced them, and how that information is combined with the NBP
// belief, which used the same depth.

#include <Eigen/Core>
#include <vector>

#include "clutterscope/estimator/mixture.hpp"

namespace clutterscope::estimator {

// The per-pixel depth noise of a described sensor (datasets::SensorOptions, sensor.json).
struct PixelNoise {
  // Axial sigma(z) = a + b (z - z0)^2 (Nguyen, Izadi & Lovell 2012), metres.
  double a_m = 0, b_per_m = 0, z0_m = 0;
  double quantisation_m = 0;        // output depth step (uniform rounding error)
  double disparity_step_per_m = 0;  // disparity quantisation: depth step = this * z^2
  // Image pixels whose depth errors are one (>= 1): the matching window's area
  // (matching_window_pixels); 1 for a sensor without one.
  double correlated_pixels = 1;
};

// The variance of one pixel's depth at z (m^2): sigma(z)^2 plus the rounding errors of the
// output step and of the disparity step, each step^2 / 12.
double depth_variance(const PixelNoise& noise, double z_m);

// Image pixels per independent depth error of a sensor that matches in a square window of
// 2 * window_half_px sensor pixels (structured light, stereo): every depth inside one window
// shares its correlation peak, so its errors are one. lateral_scale: image pixels per sensor
// pixel (camera fx / the depth sensor's focal length, 1 when not known). At least 1.
double matching_window_pixels(double window_half_px, double lateral_scale);

// A robust variance of residuals: (1.4826 MAD)^2, the MAD about their median (the variance
// for Gaussian residuals, unmoved by the few of other surfaces). 0 for no residuals.
double robust_variance(std::vector<double> residuals);

// Image pixels per independent error of a residual image (width x height, row-major, NaN where
// no residual), from the lag-1 correlations rho_u, rho_v of horizontally and vertically
// neighbouring residuals: a separable AR(1) field, whose mean of n values has the variance of
// n / c independent ones, c = (1 + rho_u) / (1 - rho_u) * (1 + rho_v) / (1 - rho_v) (negative
// correlations count as 0). Clamped to [1, residual count]; 1 with fewer than 2 pairs.
double correlated_pixels_from_residuals(const std::vector<double>& residuals, int width,
                                        int height);

// The fit's information about the position from N pixels: the inverse of the covariance
//   (c s^2 + N e^2) H^-1 + b^2 M^-2,   M = H / N,
// H = sum over the pixels of n n^T (model normals), c pixels per independent error of variance
// s^2 (the sensor's noise, which averages over the pixels), e^2 the residual variance beyond
// the sensor's (the model's surface against the depth: the same error on every pixel, which
// does not average), and b^2 the variance of the mean normal-weighted residual bias (occlusion
// boundaries, say): the point-to-plane fit moves by M^-1 times that mean,
// so along a direction that only a share m of the pixels' normals faces (an eigenvalue of M)
// the bias moves it by b / m, not b / sqrt(m). Per eigenvector of M with eigenvalue m:
// information N m^2 / ((c s^2 + N e^2) m + N b^2), zero where m = 0; b = 0 gives H / (c s^2 +
// N e^2). Symmetric; zero for no pixels. Throws std::invalid_argument for s^2 <= 0, c < 1,
// e^2 < 0 or b^2 < 0.
Eigen::Matrix3d pixel_information(const Eigen::Matrix3d& normal_sum, int pixels,
                                  double noise_variance, double correlated_pixels,
                                  double excess_variance, double bias_variance);

// The belief's bound on the position: its covariance (particles and kernels) plus the Monte
// Carlo error of a weighted sample, the spread of its particles (unweighted: where the
// proposal put them) over the effective sample size. With equal weights it adds 1/M of the
// covariance; where the weights collapsed onto one particle (ESS 1) it is the particles'
// spread, not the kernel of the one that won.
Eigen::Matrix3d belief_bound(const GaussianMixture& belief);

// The spread of other fits about an estimate, when the data cannot tell them from it: the
// second moment about `estimate` of the estimate and the others with equal weights,
// sum_i (f_i - estimate)(f_i - estimate)^T / (1 + n). Zero for no others; one other at
// distance d along u gives (d^2 / 2) u u^T, so that the other fit lies at NEES 2 along u.
// Throws std::invalid_argument for a non-finite position.
Eigen::Matrix3d other_fits_spread(const Eigen::Vector3d& estimate,
                                  const std::vector<Eigen::Vector3d>& others);

// The covariance of a position known from two sources that share their data (the fit and a
// belief from the same depth): in every direction, the more precise of the two and never
// their product. In the belief's whitened frame (B = L L^T; u_i, l_i the eigenvectors and
// eigenvalues of L^T J L) the variance along u_i is 1 / max(l_i, 1):
// Sigma = L U diag(1 / max(l, 1)) U^T L^T. With commuting B and J: per common eigenvector min(b_i,
// 1 / j_i). J = 0 gives B; B = J^-1 gives B (independent fusion would halve it). Throws
// std::invalid_argument for a belief that is not positive definite or a non-finite J.
Eigen::Matrix3d information_maximum(const Eigen::Matrix3d& belief_covariance,
                                    const Eigen::Matrix3d& fit_information);

// The covariance of a position that two bounds from the same data describe (the spread of the
// K fits from the belief's samples and the fit's information per pixel: both measure the
// depth's noise): in every direction the larger of the two, never their sum. In the frame
// whitened by A (A = L L^T; u_i, c_i the eigenvectors and eigenvalues of L^-1 C L^-T):
// Sigma = L U diag(max(c, 1)) U^T L^T, which lies above both and below their sum in the
// Loewner order (A, C <= Sigma <= A + C). With commuting A and C: per common eigenvector
// max(a_i, c_i). C = 0 gives A; C = A gives A (their sum would double it). Throws
// std::invalid_argument for an A that is not positive definite or a C that is not finite.
Eigen::Matrix3d covariance_maximum(const Eigen::Matrix3d& a, const Eigen::Matrix3d& c);

// The position that goes with information_maximum: along every direction u_i the mean of the
// source whose variance is taken there, the fit's where l_i >= 1, else the belief's
// (x = L U (D U^T L^-1 belief_mean + (I - D) U^T L^-1 fit_mean), D = diag(l_i < 1)). With
// commuting B and J: per common eigenvector the more precise source's coordinate. Throws as
// information_maximum.
Eigen::Vector3d information_maximum_mean(const Eigen::Vector3d& belief_mean,
                                         const Eigen::Matrix3d& belief_covariance,
                                         const Eigen::Vector3d& fit_mean,
                                         const Eigen::Matrix3d& fit_information);

}  // namespace clutterscope::estimator
