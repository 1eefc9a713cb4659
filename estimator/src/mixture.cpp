#include "clutterscope/estimator/mixture.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "sampling.hpp"

namespace clutterscope::estimator {

bool GaussianMixture::IsValid(std::string* why) const {
  auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (means.rows() < 1 || means.cols() < 1) return fail("mixture has no components");
  if (weights.size() != means.cols()) {
    std::ostringstream s;
    s << "mixture has " << means.cols() << " means but " << weights.size() << " weights";
    return fail(s.str());
  }
  if (variances.rows() != means.rows() ||
      (variances.cols() != 1 && variances.cols() != means.cols()))
    return fail("mixture variances must be d x 1 or d x M");
  if (!means.allFinite()) return fail("mixture means are not finite");
  if (!variances.allFinite() || (variances.array() <= 0).any())
    return fail("mixture variances must be finite and > 0");
  if (!weights.allFinite() || (weights.array() < 0).any())
    return fail("mixture weights must be finite and >= 0");
  if (std::abs(weights.sum() - 1) > 1e-6) {
    std::ostringstream s;
    s << "mixture weights sum to " << weights.sum() << ", expected 1";
    return fail(s.str());
  }
  return true;
}

GaussianMixture make_kernel_density(const Eigen::MatrixXd& means,
                                    const Eigen::VectorXd& variances) {
  GaussianMixture mixture;
  mixture.means = means;
  mixture.weights = Eigen::VectorXd::Constant(means.cols(), 1.0 / means.cols());
  mixture.variances = variances;
  return mixture;
}

Eigen::VectorXd rule_of_thumb_bandwidth(const Eigen::MatrixXd& samples,
                                        const Eigen::VectorXd& weights, double min_variance) {
  const double d = static_cast<double>(samples.rows());
  const Eigen::VectorXd mean = samples * weights;
  const Eigen::VectorXd variance = (samples.colwise() - mean).array().square().matrix() * weights;
  const double n = effective_sample_size(weights);
  const double factor = std::pow(4.0 / ((d + 2.0) * n), 2.0 / (d + 4.0));
  return (variance * factor).cwiseMax(min_variance);
}

Eigen::MatrixXd sample_mixture(const GaussianMixture& mixture, int count, std::mt19937_64& rng) {
  const int d = mixture.dimension();
  Eigen::VectorXd cumulative(mixture.size());
  double total = 0;
  for (int i = 0; i < mixture.size(); ++i) cumulative[i] = (total += mixture.weights[i]);
  Eigen::MatrixXd samples(d, count);
  detail::AntitheticNormal normal(d);
  // Stratified (systematic) component draws: unbiased with less noise than independent draws.
  const double stride = total / count;
  double position = std::uniform_real_distribution<double>(0, stride)(rng);
  int i = 0;
  for (int j = 0; j < count; ++j, position += stride) {
    while (i + 1 < mixture.size() && cumulative[i] < position) ++i;
    const auto var = mixture.component_variances(i);
    const double* z = normal.next(rng);
    for (int k = 0; k < d; ++k) samples(k, j) = mixture.means(k, i) + std::sqrt(var[k]) * z[k];
  }
  return samples;
}

Eigen::VectorXd log_evaluate(const GaussianMixture& mixture, const Eigen::MatrixXd& points) {
  const int d = mixture.dimension();
  const int m = mixture.size();
  const double log_two_pi = std::log(2 * M_PI);
  if (mixture.shared_bandwidth() && points.cols() > 0) {
    // All squared distances as one matrix product (NBP divides M x M of them out of its message
    // weights), centred first so that the expansion does not cancel.
    const Eigen::VectorXd centre = points.rowwise().mean();
    const Eigen::VectorXd precision = mixture.variances.col(0).cwiseInverse();
    const Eigen::MatrixXd a = mixture.means.colwise() - centre;
    const Eigen::MatrixXd b = points.colwise() - centre;
    Eigen::MatrixXd table = a.transpose() * precision.asDiagonal() * b;  // m x N
    table.colwise() -=
        0.5 *
        (a.array().square().colwise() * precision.array()).colwise().sum().matrix().transpose();
    table.rowwise() -=
        0.5 * (b.array().square().colwise() * precision.array()).colwise().sum().matrix();
    table = table.cwiseMin(0.0);  // rounding can make -1/2 (a - b)' P (a - b) slightly positive
    table.colwise() += mixture.weights.array().log().matrix();
    const double constant = -0.5 * (d * log_two_pi + mixture.variances.col(0).array().log().sum());
    Eigen::VectorXd result(points.cols());
    for (Eigen::Index j = 0; j < points.cols(); ++j) {
      const double top = table.col(j).maxCoeff();
      result[j] = std::isfinite(top)
                      ? constant + top + std::log((table.col(j).array() - top).exp().sum())
                      : top;
    }
    return result;
  }
  // Per-component constant: log w_i - 0.5 * sum_k log(2 pi var_ik).
  Eigen::ArrayXd constant(m);
  Eigen::ArrayXXd precision(d, m);
  for (int i = 0; i < m; ++i) {
    const auto var = mixture.component_variances(i);
    precision.col(i) = var.array().inverse();
    constant[i] = std::log(mixture.weights[i]) - 0.5 * (d * log_two_pi + var.array().log().sum());
  }
  Eigen::VectorXd result(points.cols());
  Eigen::ArrayXd log_terms(m);
  for (int j = 0; j < points.cols(); ++j) {
    const Eigen::ArrayXXd diff = mixture.means.array().colwise() - points.col(j).array();
    log_terms = constant - 0.5 * (diff.square() * precision).colwise().sum().transpose();
    const double top = log_terms.maxCoeff();
    result[j] = std::isfinite(top) ? top + std::log((log_terms - top).exp().sum()) : top;
  }
  return result;
}

Eigen::VectorXd mixture_mean(const GaussianMixture& mixture) {
  return mixture.means * mixture.weights;
}

Eigen::MatrixXd mixture_covariance(const GaussianMixture& mixture) {
  const Eigen::VectorXd mean = mixture_mean(mixture);
  const Eigen::MatrixXd centred = mixture.means.colwise() - mean;
  Eigen::MatrixXd covariance = centred * mixture.weights.asDiagonal() * centred.transpose();
  if (mixture.shared_bandwidth()) {
    covariance.diagonal() += mixture.variances.col(0);
  } else {
    covariance.diagonal() += mixture.variances * mixture.weights;
  }
  return covariance;
}

bool normalise_log_weights(const Eigen::VectorXd& log_weights, Eigen::VectorXd* weights) {
  const int n = static_cast<int>(log_weights.size());
  double top = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i)
    if (std::isfinite(log_weights[i])) top = std::max(top, log_weights[i]);
  weights->resize(n);
  if (!std::isfinite(top)) {
    weights->setConstant(1.0 / n);
    return false;
  }
  for (int i = 0; i < n; ++i)
    (*weights)[i] = std::isfinite(log_weights[i]) ? std::exp(log_weights[i] - top) : 0.0;
  *weights /= weights->sum();
  return true;
}

double effective_sample_size(const Eigen::VectorXd& weights) {
  const double sum_squares = weights.squaredNorm();
  return sum_squares > 0 ? 1.0 / sum_squares : 0.0;
}

double tempering_exponent(const Eigen::VectorXd& base, const Eigen::VectorXd& tempered,
                          double min_fraction) {
  if (base.size() != tempered.size())
    throw std::invalid_argument("tempering: base and tempered log-weights differ in size");
  Eigen::VectorXd prior;
  normalise_log_weights(base, &prior);
  const auto fraction_at = [&](double beta) {
    double top = -std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < base.size(); ++i)
      if (prior[i] > 0 && std::isfinite(tempered[i])) top = std::max(top, beta * tempered[i]);
    if (!std::isfinite(top)) return 1.0;  // nothing the likelihood can reweight
    double sum = 0, sum_squares = 0;
    for (Eigen::Index i = 0; i < base.size(); ++i) {
      if (!(prior[i] > 0) || !std::isfinite(tempered[i])) continue;  // -inf: weight 0 at any beta
      const double e = std::exp(beta * tempered[i] - top);
      sum += prior[i] * e;
      sum_squares += prior[i] * e * e;
    }
    return sum_squares > 0 ? sum * sum / sum_squares : 0.0;
  };
  if (fraction_at(1.0) >= min_fraction) return 1.0;
  double low = 0.0, high = 1.0;  // fraction(low) >= min_fraction > fraction(high)
  while (high - low > 1e-4) {
    const double middle = 0.5 * (low + high);
    (fraction_at(middle) >= min_fraction ? low : high) = middle;
  }
  return low;
}

std::vector<int> systematic_resample(const Eigen::VectorXd& weights, int count,
                                     std::mt19937_64& rng) {
  std::vector<int> indices(count);
  const double step = 1.0 / count;
  double position = std::uniform_real_distribution<double>(0, step)(rng);
  double cumulative = weights[0];
  int i = 0;
  const int last = static_cast<int>(weights.size()) - 1;
  for (int j = 0; j < count; ++j) {
    while (position > cumulative && i < last) cumulative += weights[++i];
    indices[j] = i;
    position += step;
  }
  return indices;
}

}  // namespace clutterscope::estimator
