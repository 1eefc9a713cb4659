#include "clutterscope/estimator/product.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sampling.hpp"

namespace clutterscope::estimator {
namespace {

void check_inputs(const MixtureList& inputs) {
  if (inputs.empty()) throw std::invalid_argument("product of mixtures needs at least one input");
  const int d = inputs[0]->dimension();
  for (size_t j = 0; j < inputs.size(); ++j) {
    std::string why;
    if (!inputs[j]->IsValid(&why))
      throw std::invalid_argument("product input " + std::to_string(j) + ": " + why);
    if (inputs[j]->dimension() != d)
      throw std::invalid_argument("product inputs have different dimensions");
  }
}

// log-pairwise label table L(l, m) = -1/2 sum_k c_k (mu_a(k, l) - mu_b(k, m))^2.
Eigen::MatrixXd pair_log_table(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                               const Eigen::VectorXd& c) {
  const Eigen::VectorXd a2 = (a.array().square().colwise() * c.array()).colwise().sum();
  const Eigen::VectorXd b2 = (b.array().square().colwise() * c.array()).colwise().sum();
  Eigen::MatrixXd table = a.transpose() * c.asDiagonal() * b;
  table.colwise() -= 0.5 * a2;
  table.rowwise() -= 0.5 * b2.transpose();
  return table.cwiseMin(0.0);  // rounding can make -1/2 (a - b)^2 slightly positive
}

// Draws x from the product of the chosen components of shared-bandwidth inputs.
void draw_from_components(const MixtureList& inputs, const int* labels, std::mt19937_64& rng,
                          detail::AntitheticNormal& normal, double* x) {
  const int d = inputs[0]->dimension();
  const double* z = normal.next(rng);
  for (int k = 0; k < d; ++k) {
    double precision = 0, weighted_mean = 0;
    for (size_t j = 0; j < inputs.size(); ++j) {
      const double p = 1.0 / inputs[j]->component_variances(labels[j])[k];
      precision += p;
      weighted_mean += p * inputs[j]->means(k, labels[j]);
    }
    x[k] = weighted_mean / precision + z[k] / std::sqrt(precision);
  }
}

Eigen::VectorXd log_weights_of(const GaussianMixture& m) { return m.weights.array().log(); }

Eigen::MatrixXd sample_exact_labels(const MixtureList& inputs, int count, std::mt19937_64& rng) {
  const int d = inputs[0]->dimension();
  const int n_inputs = static_cast<int>(inputs.size());
  Eigen::MatrixXd samples(d, count);
  detail::AntitheticNormal normal(d);
  int labels[3] = {0, 0, 0};
  if (n_inputs == 1) {
    return sample_mixture(*inputs[0], count, rng);
  }
  std::vector<Eigen::VectorXd> precision(n_inputs);
  Eigen::VectorXd total_precision = Eigen::VectorXd::Zero(d);
  for (int j = 0; j < n_inputs; ++j) {
    precision[j] = inputs[j]->variances.col(0).cwiseInverse();
    total_precision += precision[j];
  }
  auto coupling = [&](int j, int k) {
    return Eigen::VectorXd(precision[j].cwiseProduct(precision[k]).cwiseQuotient(total_precision));
  };
  const Eigen::VectorXd lw0 = log_weights_of(*inputs[0]);
  const Eigen::VectorXd lw1 = log_weights_of(*inputs[1]);
  const int m0 = inputs[0]->size(), m1 = inputs[1]->size();
  Eigen::MatrixXd l01 = pair_log_table(inputs[0]->means, inputs[1]->means, coupling(0, 1));
  l01.colwise() += lw0;
  l01.rowwise() += lw1.transpose();
  Eigen::MatrixXd pair_log = l01;

  // D = 3: scaled exp tables (or log tables after underflow), rows are labels of inputs 0, 1.
  Eigen::MatrixXd f02, g12;
  bool third_in_log_space = false;
  if (n_inputs == 3) {
    const Eigen::VectorXd lw2 = log_weights_of(*inputs[2]);
    Eigen::MatrixXd l02 = pair_log_table(inputs[0]->means, inputs[2]->means, coupling(0, 2));
    l02.rowwise() += lw2.transpose();
    Eigen::MatrixXd l12 = pair_log_table(inputs[1]->means, inputs[2]->means, coupling(1, 2));
    const Eigen::VectorXd r0 = l02.rowwise().maxCoeff();
    const Eigen::VectorXd r1 = l12.rowwise().maxCoeff();
    f02 = (l02.colwise() - r0).array().exp();
    g12 = (l12.colwise() - r1).array().exp();
    const Eigen::MatrixXd z = f02 * g12.transpose();
    // Upper bound of each pair's log mass, to detect underflow of the scaled products.
    Eigen::MatrixXd bound = pair_log;
    bound.colwise() += r0;
    bound.rowwise() += r1.transpose();
    pair_log = bound.array() + z.array().log();
    const double max_bound = bound.maxCoeff();
    if (!(pair_log.maxCoeff() > max_bound - 600.0)) {
      // Badly separated inputs: the scaled products underflowed; sum over l_2 in log space.
      for (int a = 0; a < m0; ++a) {
        for (int b = 0; b < m1; ++b) {
          const Eigen::ArrayXd terms = (l02.row(a) + l12.row(b)).array();
          const double top = terms.maxCoeff();
          pair_log(a, b) = l01(a, b) + top + std::log((terms - top).exp().sum());
        }
      }
      // l_2 | (l_0, l_1) is then drawn from the log tables too.
      f02 = l02;
      g12 = l12;
      third_in_log_space = true;
    }
  }
  // Cumulative pair distribution (column-major: index = a + m0 * b).
  const double top = pair_log.maxCoeff();
  if (!std::isfinite(top)) throw std::invalid_argument("product of mixtures has zero mass");
  Eigen::VectorXd cumulative(static_cast<Eigen::Index>(m0) * m1);
  double total = 0;
  for (Eigen::Index i = 0; i < cumulative.size(); ++i)
    cumulative[i] = (total += std::exp(pair_log.data()[i] - top));
  const int m2 = n_inputs == 3 ? inputs[2]->size() : 0;
  Eigen::VectorXd third(m2);
  // Stratified (systematic) draws of the pairs: unbiased, with less Monte-Carlo noise in the
  // set of samples than independent draws (NBP messages are sets, order does not matter).
  const double stride = total / count;
  double position = std::uniform_real_distribution<double>(0, stride)(rng);
  Eigen::Index pair = 0;
  for (int s = 0; s < count; ++s, position += stride) {
    while (pair + 1 < cumulative.size() && cumulative[pair] < position) ++pair;
    labels[0] = static_cast<int>(pair % m0);
    labels[1] = static_cast<int>(pair / m0);
    if (n_inputs == 3) {
      double run = 0;
      if (third_in_log_space) {
        const Eigen::ArrayXd terms = (f02.row(labels[0]) + g12.row(labels[1])).array();
        const double t = terms.maxCoeff();
        for (int c = 0; c < m2; ++c) third[c] = (run += std::exp(terms[c] - t));
      } else {
        for (int c = 0; c < m2; ++c) third[c] = (run += f02(labels[0], c) * g12(labels[1], c));
      }
      labels[2] = detail::draw_cumulative(third.data(), m2, rng);
    }
    draw_from_components(inputs, labels, rng, normal, samples.col(s).data());
  }
  return samples;
}

Eigen::MatrixXd sample_gibbs(const MixtureList& inputs, int count, int sweeps,
                             std::mt19937_64& rng) {
  const int d = inputs[0]->dimension();
  const int n_inputs = static_cast<int>(inputs.size());
  Eigen::MatrixXd samples(d, count);
  detail::AntitheticNormal normal(d);
  std::vector<Eigen::VectorXd> log_weights(n_inputs);
  std::vector<Eigen::ArrayXXd> precisions(n_inputs);
  int max_m = 0;
  for (int j = 0; j < n_inputs; ++j) {
    log_weights[j] = log_weights_of(*inputs[j]);
    precisions[j] = inputs[j]->variances.array().inverse();
    max_m = std::max(max_m, inputs[j]->size());
  }
  std::vector<int> labels(n_inputs);
  Eigen::ArrayXd log_p(max_m), cumulative(max_m);
  Eigen::ArrayXXd total(d, max_m);
  Eigen::ArrayXd precision(d), weighted_mean(d);

  // Resamples label j given the labels of inputs in [0, n_used) other than j.
  auto draw_label = [&](int j, int n_used) {
    const GaussianMixture& mix = *inputs[j];
    const int m = mix.size();
    precision.setZero();
    weighted_mean.setZero();
    bool any_other = false;
    for (int k = 0; k < n_used; ++k) {
      if (k == j) continue;
      const Eigen::ArrayXd p = precisions[k].col(inputs[k]->shared_bandwidth() ? 0 : labels[k]);
      precision += p;
      weighted_mean += p * inputs[k]->means.col(labels[k]).array();
      any_other = true;
    }
    if (!any_other) {
      log_p.head(m) = log_weights[j].array();
    } else {
      const Eigen::ArrayXd other_mean = weighted_mean / precision;
      const Eigen::ArrayXd other_var = precision.inverse();
      if (mix.shared_bandwidth()) {
        const Eigen::ArrayXd s = mix.variances.col(0).array() + other_var;
        const Eigen::ArrayXd inv_s = s.inverse();
        log_p.head(m) =
            log_weights[j].array() -
            0.5 * ((mix.means.array().colwise() - other_mean).square().colwise() * inv_s)
                      .colwise()
                      .sum()
                      .transpose();
      } else {
        total.leftCols(m) = mix.variances.array().colwise() + other_var;
        log_p.head(m) =
            log_weights[j].array() -
            0.5 * ((mix.means.array().colwise() - other_mean).square() / total.leftCols(m) +
                   total.leftCols(m).log())
                      .colwise()
                      .sum()
                      .transpose();
      }
    }
    const double top = log_p.head(m).maxCoeff();
    double run = 0;
    for (int c = 0; c < m; ++c) cumulative[c] = (run += std::exp(log_p[c] - top));
    labels[j] = detail::draw_cumulative(cumulative.data(), m, rng);
  };

  for (int s = 0; s < count; ++s) {
    for (int j = 0; j < n_inputs; ++j) draw_label(j, j + 1);  // sequential initialisation
    for (int sweep = 0; sweep < sweeps; ++sweep)
      for (int j = 0; j < n_inputs; ++j) draw_label(j, n_inputs);
    draw_from_components(inputs, labels.data(), rng, normal, samples.col(s).data());
  }
  return samples;
}

}  // namespace

bool ProductOptions::IsValid(std::string* why) const {
  if (gibbs_sweeps < 0) {
    if (why) *why = "gibbs_sweeps must be >= 0, got " + std::to_string(gibbs_sweeps);
    return false;
  }
  return true;
}

namespace {

// Folds every one-component input into another input exactly: a shared-bandwidth mixture
// times a Gaussian is again a shared-bandwidth mixture (weights w_i N(a_i; mu, h + v), means
// the per-component products, variance (1/h + 1/v)^-1). Detection priors and messages from
// fixed nodes are single Gaussians, so scene products shrink to their hidden neighbours.
MixtureList fold_single_components(const MixtureList& inputs, GaussianMixture* storage) {
  MixtureList multi;
  Eigen::VectorXd precision, weighted_mean;
  bool any_single = false;
  for (const GaussianMixture* m : inputs) {
    if (m->size() > 1 || !m->shared_bandwidth()) {
      multi.push_back(m);
      continue;
    }
    const Eigen::VectorXd p = m->variances.col(0).cwiseInverse();
    if (!any_single) {
      precision = Eigen::VectorXd::Zero(p.size());
      weighted_mean = Eigen::VectorXd::Zero(p.size());
    }
    any_single = true;
    precision += p;
    weighted_mean += p.cwiseProduct(m->means.col(0));
  }
  if (!any_single) return inputs;
  const Eigen::VectorXd single_mean = weighted_mean.cwiseQuotient(precision);
  const Eigen::VectorXd single_var = precision.cwiseInverse();
  int target = -1;
  for (int j = 0; j < static_cast<int>(multi.size()); ++j)
    if (multi[j]->shared_bandwidth()) target = j;
  if (target < 0) {
    *storage = make_kernel_density(single_mean, single_var);
    multi.push_back(storage);
    return multi;
  }
  const GaussianMixture& a = *multi[target];
  const Eigen::ArrayXd h = a.variances.col(0).array();
  const Eigen::ArrayXd s = h + single_var.array();
  Eigen::VectorXd log_w =
      a.weights.array().log() -
      0.5 * ((a.means.array().colwise() - single_mean.array()).square().colwise() / s)
                .colwise()
                .sum()
                .transpose();
  storage->variances = (h.inverse() + single_var.array().inverse()).inverse().matrix();
  storage->means =
      ((a.means.array().colwise() / h).colwise() + single_mean.array() / single_var.array())
          .colwise() *
      storage->variances.col(0).array();
  if (!normalise_log_weights(log_w, &storage->weights))
    throw std::invalid_argument("product of mixtures has zero mass");
  multi[target] = storage;
  return multi;
}

}  // namespace

bool exact_label_sampling_applies(const MixtureList& inputs) {
  if (inputs.empty()) return false;
  int multi = 0;
  for (const GaussianMixture* m : inputs) {
    if (!m->shared_bandwidth()) return false;
    if (m->size() > 1) ++multi;
  }
  return multi <= 3;
}

Eigen::MatrixXd sample_product(const MixtureList& inputs, int count, const ProductOptions& options,
                               std::mt19937_64& rng) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  check_inputs(inputs);
  if (count < 0) throw std::invalid_argument("sample count must be >= 0");
  const bool exact = exact_label_sampling_applies(inputs);
  if (options.method == ProductMethod::kExactLabels && !exact)
    throw std::invalid_argument(
        "exact label sampling needs at most 3 multi-component inputs with shared bandwidths");
  if (inputs.size() == 1) return sample_mixture(*inputs[0], count, rng);
  if (options.method == ProductMethod::kGibbs)
    return sample_gibbs(inputs, count, options.gibbs_sweeps, rng);
  GaussianMixture folded_storage;
  const MixtureList folded = fold_single_components(inputs, &folded_storage);
  if (folded.size() == 1) return sample_mixture(*folded[0], count, rng);
  if (exact) return sample_exact_labels(folded, count, rng);
  return sample_gibbs(folded, count, options.gibbs_sweeps, rng);
}

GaussianMixture exact_product(const MixtureList& inputs, long max_components) {
  check_inputs(inputs);
  const int d = inputs[0]->dimension();
  const int n_inputs = static_cast<int>(inputs.size());
  long n = 1;
  for (const GaussianMixture* m : inputs) {
    n *= m->size();
    if (n > max_components) {
      std::ostringstream s;
      s << "exact product would have more than " << max_components << " components";
      throw std::invalid_argument(s.str());
    }
  }
  GaussianMixture product;
  product.means.resize(d, n);
  product.variances.resize(d, n);
  Eigen::VectorXd log_w(n);
  std::vector<int> labels(n_inputs, 0);
  const double log_two_pi = std::log(2 * M_PI);
  for (long c = 0; c < n; ++c) {
    double lw = 0;
    for (int j = 0; j < n_inputs; ++j) lw += std::log(inputs[j]->weights[labels[j]]);
    for (int k = 0; k < d; ++k) {
      double precision = 0, pm = 0, pmm = 0, log_var = 0;
      for (int j = 0; j < n_inputs; ++j) {
        const double v = inputs[j]->component_variances(labels[j])[k];
        const double mu = inputs[j]->means(k, labels[j]);
        precision += 1 / v;
        pm += mu / v;
        pmm += mu * mu / v;
        log_var += std::log(v);
      }
      product.means(k, c) = pm / precision;
      product.variances(k, c) = 1 / precision;
      // log of the integral of the product of the 1-D Gaussians in dimension k.
      lw += -0.5 * ((n_inputs - 1) * log_two_pi + log_var + std::log(precision) + pmm -
                    pm * pm / precision);
    }
    log_w[c] = lw;
    for (int j = 0; j < n_inputs; ++j) {  // mixed-radix increment, input 0 fastest
      if (++labels[j] < inputs[j]->size()) break;
      labels[j] = 0;
    }
  }
  if (!normalise_log_weights(log_w, &product.weights))
    throw std::invalid_argument("product of mixtures has zero mass");
  return product;
}

}  // namespace clutterscope::estimator
