#include "clutterscope/estimator/bench.hpp"

#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <memory>
#include <random>

#include "clutterscope/estimator/mixture.hpp"
#include "clutterscope/estimator/nbp.hpp"
#include "clutterscope/estimator/potentials.hpp"
#include "clutterscope/estimator/product.hpp"

namespace clutterscope::estimator {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// CPU time of the calling thread: on shared, oversubscribed machines wall-clock minima still
// include waiting for a core; the thread's own CPU time does not.
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * t.tv_sec + 1e-6 * t.tv_nsec;
}

class GaussianUnary : public PointwiseLogPotential {
 public:
  GaussianUnary(Eigen::Vector3d mean, double sigma) : mean_(mean), sigma_(sigma) {}
  void evaluate(const Eigen::MatrixXd& points, Eigen::VectorXd* log_values) override {
    *log_values =
        -0.5 * (points.colwise() - mean_).colwise().squaredNorm().transpose() / (sigma_ * sigma_);
  }

 private:
  Eigen::Vector3d mean_;
  double sigma_;
};

}  // namespace

ProductBenchmark benchmark_product(int particles, int inputs, int products,
                                   const std::vector<int>& gibbs_sweeps, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const int d = 3;
  std::vector<GaussianMixture> mixtures;
  for (int j = 0; j < inputs; ++j) {
    // Samples of a bimodal density, shifted per input, as KDE messages.
    Eigen::MatrixXd means(d, particles);
    for (int i = 0; i < particles; ++i)
      for (int k = 0; k < d; ++k) means(k, i) = normal(rng) + (i % 2 == 0 ? 1.0 : -1.0) + 0.3 * j;
    const Eigen::VectorXd w = Eigen::VectorXd::Constant(particles, 1.0 / particles);
    mixtures.push_back(make_kernel_density(means, rule_of_thumb_bandwidth(means, w, 1e-12)));
  }
  MixtureList list;
  for (const GaussianMixture& m : mixtures) list.push_back(&m);
  const GaussianMixture exact = exact_product(list, 20'000'000);
  const Eigen::VectorXd exact_mean = mixture_mean(exact);
  const Eigen::VectorXd exact_var = mixture_covariance(exact).diagonal();

  ProductBenchmark bench;
  bench.inputs = inputs;
  bench.dimension = d;
  bench.particles = particles;
  bench.products = products;
  std::vector<std::pair<std::string, ProductOptions>> methods;
  ProductOptions exact_labels;
  exact_labels.method = ProductMethod::kExactLabels;
  methods.emplace_back("exact-labels", exact_labels);
  for (int sweeps : gibbs_sweeps) {
    ProductOptions gibbs;
    gibbs.method = ProductMethod::kGibbs;
    gibbs.gibbs_sweeps = sweeps;
    methods.emplace_back("gibbs-" + std::to_string(sweeps), gibbs);
  }
  for (const auto& [name, options] : methods) {
    Eigen::MatrixXd pooled(d, static_cast<Eigen::Index>(products) * particles);
    ProductSamplerTiming t;
    t.method = name;
    t.ms_per_product = std::numeric_limits<double>::infinity();
    // Timed per product, keeping the fastest: the machines are shared.
    t.cpu_ms_per_product = std::numeric_limits<double>::infinity();
    for (int p = 0; p < products; ++p) {
      const auto start = Clock::now();
      const double cpu_start = thread_cpu_ms();
      pooled.middleCols(static_cast<Eigen::Index>(p) * particles, particles) =
          sample_product(list, particles, options, rng);
      t.cpu_ms_per_product = std::min(t.cpu_ms_per_product, thread_cpu_ms() - cpu_start);
      t.ms_per_product = std::min(t.ms_per_product, ms_since(start));
    }
    const double n = static_cast<double>(pooled.cols());
    const Eigen::VectorXd mean = pooled.rowwise().mean();
    const Eigen::VectorXd var =
        (pooled.colwise() - mean).array().square().rowwise().sum() / (n - 1);
    // Samples within one product are stratified, not independent; products are independent,
    // so the standard error uses the exact variance over all n samples (conservative enough
    // for a bias indicator).
    t.mean_error_se =
        ((mean - exact_mean).array().abs() / (exact_var.array() / n).sqrt()).maxCoeff();
    t.variance_ratio_min = (var.array() / exact_var.array()).minCoeff();
    t.variance_ratio_max = (var.array() / exact_var.array()).maxCoeff();
    bench.methods.push_back(t);
  }
  return bench;
}

NbpBenchmark benchmark_nbp(const std::vector<int>& particles, int iterations, uint64_t seed) {
  NbpBenchmark bench;
  bench.iterations = iterations;
  PairwiseMrf mrf;
  mrf.dimension = 3;
  const Eigen::Vector3d table_size(0.6, 0.4, 0.02), box(0.08, 0.06, 0.05);
  MrfNode table;
  table.fixed = true;
  table.fixed_position = Eigen::Vector3d(0, 0, -0.01);
  mrf.nodes.push_back(table);
  std::vector<Eigen::Vector3d> truth;
  for (int i = 0; i < 10; ++i) {
    const bool stacked = i >= 6;
    const Eigen::Vector3d base = stacked ? truth[i - 6] : Eigen::Vector3d(-0.25 + 0.1 * i, 0, 0);
    truth.push_back(stacked ? Eigen::Vector3d(base + Eigen::Vector3d(0, 0, box.z()))
                            : Eigen::Vector3d(base.x(), 0.05 * ((i % 2) ? 1 : -1), box.z() / 2));
    MrfNode node;
    node.initial = make_kernel_density(truth.back() + Eigen::Vector3d(0.01, -0.01, 0.005),
                                       Eigen::Vector3d::Constant(0.02 * 0.02));
    node.unary_mixture = node.initial;
    node.unary = std::make_shared<GaussianUnary>(truth.back(), 0.01);
    mrf.nodes.push_back(node);
    const int parent = stacked ? 1 + (i - 6) : 0;
    mrf.edges.push_back(
        {parent, static_cast<int>(mrf.nodes.size()) - 1,
         std::make_shared<SupportPotential>(parent == 0 ? table_size : box, box, 0.003)});
  }
  for (int i = 1; i < 6; ++i)
    mrf.edges.push_back({i, i + 1, std::make_shared<NonContactPotential>(box, box, 0.01)});
  std::vector<double> log_m, log_t;
  for (int m : particles) {
    NbpOptions options;
    options.particles = m;
    options.iterations = iterations;
    // The fastest of three identical runs: the machines are shared, the minimum is the cost.
    NbpResult result;
    NbpTiming row;
    row.particles = m;
    row.ms_per_run = std::numeric_limits<double>::infinity();
    row.cpu_ms_per_run = std::numeric_limits<double>::infinity();
    for (int repeat = 0; repeat < 3; ++repeat) {
      std::mt19937_64 rng(seed);
      const auto start = Clock::now();
      const double cpu_start = thread_cpu_ms();
      NbpResult run = run_nbp(mrf, options, rng);
      row.cpu_ms_per_run = std::min(row.cpu_ms_per_run, thread_cpu_ms() - cpu_start);
      const double ms = ms_since(start);
      if (ms < row.ms_per_run) {
        row.ms_per_run = ms;
        result = std::move(run);
      }
    }
    row.ms_products = 1e3 * result.summary.time_products.count();
    row.ms_unary = 1e3 * result.summary.time_unary.count();
    row.ms_pairwise = 1e3 * result.summary.time_pairwise.count();
    row.min_effective_sample_size = result.summary.final_min_effective_sample_size;
    bench.rows.push_back(row);
    log_m.push_back(std::log(m));
    log_t.push_back(std::log(row.cpu_ms_per_run));
  }
  if (log_m.size() >= 2) {
    const double n = static_cast<double>(log_m.size());
    double mx = 0, my = 0;
    for (size_t i = 0; i < log_m.size(); ++i) {
      mx += log_m[i] / n;
      my += log_t[i] / n;
    }
    double sxy = 0, sxx = 0;
    for (size_t i = 0; i < log_m.size(); ++i) {
      sxy += (log_m[i] - mx) * (log_t[i] - my);
      sxx += (log_m[i] - mx) * (log_m[i] - mx);
    }
    bench.growth_exponent = sxx > 0 ? sxy / sxx : 0;
  }
  return bench;
}

}  // namespace clutterscope::estimator
