#include "clutterscope/estimator/nbp.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace clutterscope::estimator {
namespace {

using Clock = std::chrono::steady_clock;

// An edge seen from one of its hidden nodes.
struct Incidence {
  int edge = 0;
  int neighbour = 0;
  EdgeDirection outgoing = EdgeDirection::kFirstToSecond;  // direction of this node's message
  bool sampled = false;
};

EdgeDirection reverse(EdgeDirection d) {
  return d == EdgeDirection::kFirstToSecond ? EdgeDirection::kSecondToFirst
                                            : EdgeDirection::kFirstToSecond;
}
int slot(EdgeDirection d) { return d == EdgeDirection::kFirstToSecond ? 0 : 1; }

// Weighted samples of a node's latest belief, and the log of each pointwise factor in it, so
// that a neighbour can remove its own factor (the message excludes the receiver).
struct BeliefSamples {
  Eigen::MatrixXd points;
  Eigen::VectorXd log_weights;               // normalised
  std::vector<Eigen::VectorXd> factor_logs;  // per incidence (pointwise ones filled)
};

// Task::exclude of the product of every input when the messages are drawn from it
// (kBeliefImportance) with M != T samples; the belief's own product is exclude = -1.
constexpr int kAllInputs = -2;

struct Task {
  int exclude = -1;  // incidence index whose message is left out; -1 for the belief
  int count = 0;
  int offset = 0;  // first column in the node's batch
  bool from_initial = false;
};

// Appends `source` scaled by `share` to `mixture` (per-component variances).
void append_components(const GaussianMixture& source, double share, GaussianMixture* mixture) {
  const int d = source.dimension(), old_size = mixture->size(), m = source.size();
  mixture->means.conservativeResize(d, old_size + m);
  mixture->weights.conservativeResize(old_size + m);
  mixture->variances.conservativeResize(d, old_size + m);
  mixture->means.middleCols(old_size, m) = source.means;
  mixture->weights.segment(old_size, m) = share * source.weights;
  for (int i = 0; i < m; ++i) mixture->variances.col(old_size + i) = source.component_variances(i);
}

}  // namespace

void PairwisePotential::sample(EdgeDirection, const Eigen::MatrixXd&, std::mt19937_64&,
                               Eigen::MatrixXd*) const {
  throw std::logic_error("this pairwise potential cannot be sampled");
}
bool PairwisePotential::gaussian_kernel(EdgeDirection, Eigen::VectorXd*, Eigen::VectorXd*) const {
  return false;
}
void PairwisePotential::log_factor(EdgeDirection, const Eigen::MatrixXd&, const Eigen::MatrixXd&,
                                   const Eigen::VectorXd&, Eigen::VectorXd*) const {
  throw std::logic_error("this pairwise potential has no pointwise factor");
}

GaussianPairwisePotential::GaussianPairwisePotential(Eigen::VectorXd offset,
                                                     Eigen::VectorXd variance)
    : offset_(std::move(offset)), variance_(std::move(variance)) {
  if (offset_.size() != variance_.size() || (variance_.array() <= 0).any() ||
      !offset_.allFinite() || !variance_.allFinite())
    throw std::invalid_argument("Gaussian pairwise potential needs finite offset and variance > 0");
}

void GaussianPairwisePotential::sample(EdgeDirection direction, const Eigen::MatrixXd& from,
                                       std::mt19937_64& rng, Eigen::MatrixXd* to) const {
  Eigen::VectorXd offset, variance;
  gaussian_kernel(direction, &offset, &variance);
  std::normal_distribution<double> normal;
  *to = from.colwise() + offset;
  const Eigen::VectorXd sigma = variance.cwiseSqrt();
  for (int j = 0; j < to->cols(); ++j)
    for (int k = 0; k < to->rows(); ++k) (*to)(k, j) += sigma[k] * normal(rng);
}

bool GaussianPairwisePotential::gaussian_kernel(EdgeDirection direction, Eigen::VectorXd* offset,
                                                Eigen::VectorXd* variance) const {
  *offset = direction == EdgeDirection::kFirstToSecond ? offset_ : Eigen::VectorXd(-offset_);
  *variance = variance_;
  return true;
}

bool PairwiseMrf::IsValid(std::string* why) const {
  auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (dimension < 1) return fail("MRF dimension must be >= 1");
  const int n = static_cast<int>(nodes.size());
  for (int i = 0; i < n; ++i) {
    const MrfNode& node = nodes[i];
    const std::string where = "node " + std::to_string(i) + ": ";
    if (node.fixed) {
      if (node.fixed_position.size() != dimension || !node.fixed_position.allFinite())
        return fail(where + "fixed position must be finite with " + std::to_string(dimension) +
                    " values");
      continue;
    }
    std::string reason;
    if (!node.initial.IsValid(&reason)) return fail(where + "initial mixture: " + reason);
    if (node.initial.dimension() != dimension) return fail(where + "initial mixture dimension");
    if (node.unary_mixture) {
      if (!node.unary_mixture->IsValid(&reason)) return fail(where + "unary mixture: " + reason);
      if (node.unary_mixture->dimension() != dimension)
        return fail(where + "unary mixture dimension");
    }
  }
  for (size_t e = 0; e < edges.size(); ++e) {
    const MrfEdge& edge = edges[e];
    const std::string where = "edge " + std::to_string(e) + ": ";
    if (edge.first < 0 || edge.first >= n || edge.second < 0 || edge.second >= n)
      return fail(where + "node index out of range");
    if (edge.first == edge.second) return fail(where + "self edge");
    if (!edge.potential) return fail(where + "no potential");
    if (nodes[edge.first].fixed && nodes[edge.second].fixed)
      return fail(where + "both nodes are fixed");
  }
  return true;
}

bool NbpOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (particles < 2) return fail("particles must be >= 2, got " + std::to_string(particles));
  if (iterations < 1) return fail("iterations must be >= 1, got " + std::to_string(iterations));
  if (gibbs_sweeps < 0)
    return fail("gibbs_sweeps must be >= 0, got " + std::to_string(gibbs_sweeps));
  if (belief_samples < 0)
    return fail("belief_samples must be >= 0, got " + std::to_string(belief_samples));
  if (!(min_bandwidth_variance > 0)) return fail("min_bandwidth_variance must be > 0");
  if (!(min_effective_sample_fraction >= 0) || !(min_effective_sample_fraction <= 1))
    return fail("min_effective_sample_fraction must be in [0, 1]");
  if (!(proposal_min_variance > 0)) return fail("proposal_min_variance must be > 0");
  if (!(defensive_fraction > 0) || !(defensive_fraction < 1))
    return fail("defensive_fraction must be in (0, 1)");
  if (pointwise_neighbour_samples < 1)
    return fail("pointwise_neighbour_samples must be >= 1, got " +
                std::to_string(pointwise_neighbour_samples));
  return true;
}

namespace {

// One run of Algorithm 2 over a graph, in named stages. Every stage draws from the random
// streams in the order of the paper's schedule: the initial beliefs and messages from the run's
// stream; per iteration one seed per node from it, then each node's products, pointwise factors
// and message pushes from that node's stream.
class NbpRun {
 public:
  NbpRun(const PairwiseMrf& mrf, const NbpOptions& options, std::mt19937_64& rng)
      : mrf_(mrf),
        options_(options),
        rng_(rng),
        n_(static_cast<int>(mrf.nodes.size())),
        d_(mrf.dimension),
        m_(options.particles),
        t_samples_(options.belief_samples > 0 ? options.belief_samples : options.particles),
        from_belief_(options.message_proposal == MessageProposal::kBeliefImportance),
        incidences_(n_),
        messages_(mrf.edges.size()),
        beliefs_(n_),
        next_messages_(mrf.edges.size()),
        next_beliefs_(n_),
        temperatures_(n_, 1.0) {
    product_options_.method = options.product_method;
    product_options_.gibbs_sweeps = options.gibbs_sweeps;
    result_.summary.min_effective_sample_size = std::numeric_limits<double>::infinity();
    for (int e = 0; e < static_cast<int>(mrf.edges.size()); ++e) {
      const MrfEdge& edge = mrf.edges[e];
      const bool sampled = edge.potential->is_sampled();
      incidences_[edge.first].push_back({e, edge.second, EdgeDirection::kFirstToSecond, sampled});
      incidences_[edge.second].push_back({e, edge.first, EdgeDirection::kSecondToFirst, sampled});
    }
  }

  NbpResult run() {
    const auto start = Clock::now();
    initialise();
    std::vector<uint64_t> seeds(n_);
    for (int iteration = 0; iteration < options_.iterations; ++iteration) {
      for (int t = 0; t < n_; ++t) seeds[t] = rng_();
      double iteration_min_ess = std::numeric_limits<double>::infinity();
      for (int t = 0; t < n_; ++t) {
        if (mrf_.nodes[t].fixed) {
          next_beliefs_[t] = beliefs_[t];
          continue;
        }
        std::mt19937_64 node_rng(seeds[t]);
        update_node(t, iteration, node_rng, &iteration_min_ess);
      }
      finish_iteration(iteration, iteration_min_ess);
    }
    NbpSummary& summary = result_.summary;
    if (!std::isfinite(summary.min_effective_sample_size)) summary.min_effective_sample_size = 0;
    if (!std::isfinite(summary.final_min_effective_sample_size))
      summary.final_min_effective_sample_size = 0;
    summary.time_total = Clock::now() - start;
    return std::move(result_);
  }

 private:
  // Pushes weighted samples of the sender through the edge potential into a message mixture.
  GaussianMixture push(const MrfEdge& edge, EdgeDirection direction, const Eigen::MatrixXd& points,
                       const Eigen::VectorXd& weights, std::mt19937_64& node_rng) const {
    GaussianMixture message;
    Eigen::VectorXd offset, variance;
    if (options_.message_bandwidth == MessageBandwidth::kPotentialKernel &&
        edge.potential->gaussian_kernel(direction, &offset, &variance)) {
      message.means = points.colwise() + offset;
      message.variances = variance;
    } else {
      edge.potential->sample(direction, points, node_rng, &message.means);
      message.variances =
          rule_of_thumb_bandwidth(message.means, weights, options_.min_bandwidth_variance);
    }
    message.weights = weights;
    return message;
  }

  // Beliefs from the initial mixtures, messages m^0 from them, and the constant messages of
  // fixed nodes.
  void initialise() {
    for (int t = 0; t < n_; ++t) {
      const MrfNode& node = mrf_.nodes[t];
      BeliefSamples& b = beliefs_[t];
      if (node.fixed) {
        b.points = node.fixed_position;
        b.log_weights = Eigen::VectorXd::Zero(1);
      } else {
        b.points = sample_mixture(node.initial, t_samples_, rng_);
        b.log_weights = Eigen::VectorXd::Constant(t_samples_, -std::log(double(t_samples_)));
      }
      b.factor_logs.assign(incidences_[t].size(), Eigen::VectorXd::Zero(b.points.cols()));
      for (const Incidence& inc : incidences_[t]) {
        if (!inc.sampled || mrf_.nodes[inc.neighbour].fixed) continue;
        const MrfEdge& edge = mrf_.edges[inc.edge];
        Eigen::VectorXd offset, variance;
        if (node.fixed && options_.message_bandwidth == MessageBandwidth::kPotentialKernel &&
            edge.potential->gaussian_kernel(inc.outgoing, &offset, &variance)) {
          messages_[inc.edge][slot(inc.outgoing)] =
              push(edge, inc.outgoing, node.fixed_position, Eigen::VectorXd::Ones(1), rng_);
        } else {
          const Eigen::MatrixXd from = node.fixed
                                           ? Eigen::MatrixXd(node.fixed_position.replicate(1, m_))
                                           : sample_mixture(node.initial, m_, rng_);
          messages_[inc.edge][slot(inc.outgoing)] =
              push(edge, inc.outgoing, from, Eigen::VectorXd::Constant(m_, 1.0 / m_), rng_);
        }
      }
    }
  }

  // One node's update: products, pointwise factors with tempering, then its new messages and
  // belief.
  void update_node(int t, int iteration, std::mt19937_64& node_rng, double* iteration_min_ess) {
    const std::vector<Incidence>& incs = incidences_[t];
    // With kBeliefImportance, a message whose product without the receiver would be empty
    // keeps the initial-mixture proposal: the belief would only add the receiver's message,
    // and dividing it out leaves weights that depend on how well it covers the pointwise
    // unary.
    int sampled_inputs = mrf_.nodes[t].unary_mixture ? 1 : 0;
    for (const Incidence& inc : incs) sampled_inputs += inc.sampled ? 1 : 0;
    const bool messages_from_belief = from_belief_ && sampled_inputs > 1;
    bool sends = false;
    std::vector<Task> tasks = plan_tasks(t, messages_from_belief, &sends);
    int total = 0;
    for (Task& task : tasks) {
      task.offset = total;
      total += task.count;
    }
    Eigen::MatrixXd batch(d_, total);
    Eigen::VectorXd log_weights = Eigen::VectorXd::Zero(total);
    const auto product_start = Clock::now();
    for (Task& task : tasks) sample_task(t, iteration, node_rng, &task, &batch, &log_weights);
    result_.summary.time_products += Clock::now() - product_start;

    Eigen::VectorXd factor_log = unary_factor(t, batch);
    const auto pairwise_start = Clock::now();
    BeliefSamples& belief = next_beliefs_[t];
    add_pairwise_factors(t, batch, node_rng, &belief, &factor_log);
    temper(t, factor_log, &log_weights, &belief);
    send(t, tasks, batch, log_weights, messages_from_belief && sends, node_rng, &belief,
         iteration_min_ess);
    result_.summary.time_pairwise += Clock::now() - pairwise_start;
  }

  // 1. The products to sample: one per outgoing sampled message to a hidden node, plus the
  // belief (last, so that factor_logs keep the batch's tail).
  std::vector<Task> plan_tasks(int t, bool messages_from_belief, bool* sends) const {
    const std::vector<Incidence>& incs = incidences_[t];
    std::vector<Task> tasks;
    for (int k = 0; k < static_cast<int>(incs.size()); ++k) {
      if (!incs[k].sampled || mrf_.nodes[incs[k].neighbour].fixed) continue;
      *sends = true;
      if (!messages_from_belief) tasks.push_back({k, m_});
    }
    if (messages_from_belief && *sends && t_samples_ != m_) tasks.push_back({kAllInputs, m_});
    tasks.push_back({-1, t_samples_});
    return tasks;
  }

  // Samples one task's columns of the batch, with the log proposal corrections.
  void sample_task(int t, int iteration, std::mt19937_64& node_rng, Task* task,
                   Eigen::MatrixXd* batch, Eigen::VectorXd* log_weights) {
    const MrfNode& node = mrf_.nodes[t];
    const std::vector<Incidence>& incs = incidences_[t];
    MixtureList inputs;
    if (node.unary_mixture) inputs.push_back(&*node.unary_mixture);
    for (int k = 0; k < static_cast<int>(incs.size()); ++k)
      if (incs[k].sampled && k != task->exclude)
        inputs.push_back(&messages_[incs[k].edge][slot(reverse(incs[k].outgoing))]);
    auto block = batch->middleCols(task->offset, task->count);
    if (task->exclude == -1 && options_.adaptive_belief_proposal && iteration > 0) {
      const GaussianMixture proposal = adaptive_proposal(t, inputs);
      block = sample_mixture(proposal, task->count, node_rng);
      Eigen::VectorXd log_target = Eigen::VectorXd::Zero(task->count);
      for (const GaussianMixture* input : inputs) log_target += log_evaluate(*input, block);
      log_weights->segment(task->offset, task->count) = log_target - log_evaluate(proposal, block);
    } else if (inputs.empty()) {
      task->from_initial = true;
      block = sample_mixture(node.initial, task->count, node_rng);
      log_weights->segment(task->offset, task->count) = -log_evaluate(node.initial, block);
    } else {
      block = sample_product(inputs, task->count, product_options_, node_rng);
    }
    ++result_.summary.products_sampled;
  }

  // The previous belief as a kernel density, mixed with the initial mixture and the incoming
  // messages; the belief's weights are then the product of the inputs / this proposal.
  GaussianMixture adaptive_proposal(int t, const MixtureList& inputs) const {
    const MrfNode& node = mrf_.nodes[t];
    GaussianMixture proposal;
    proposal.means.resize(d_, 0);
    GaussianMixture previous;
    previous.means = beliefs_[t].points;
    normalise_log_weights(beliefs_[t].log_weights, &previous.weights);
    previous.variances =
        rule_of_thumb_bandwidth(previous.means, previous.weights, options_.proposal_min_variance);
    const int message_count = static_cast<int>(inputs.size()) - (node.unary_mixture ? 1 : 0);
    const double defensive = options_.defensive_fraction;
    append_components(previous, 1 - defensive, &proposal);
    append_components(node.initial, message_count > 0 ? defensive / 2 : defensive, &proposal);
    for (std::size_t j = node.unary_mixture ? 1 : 0; j < inputs.size(); ++j)
      append_components(*inputs[j], defensive / 2 / message_count, &proposal);
    proposal.weights /= proposal.weights.sum();
    return proposal;
  }

  // 2. The pointwise unary for the whole batch: the start of the sum of pointwise factors
  // (tempered later; the proposal corrections stay in the log weights).
  Eigen::VectorXd unary_factor(int t, const Eigen::MatrixXd& batch) {
    const MrfNode& node = mrf_.nodes[t];
    const Eigen::Index total = batch.cols();
    Eigen::VectorXd factor_log = Eigen::VectorXd::Zero(total);
    if (!node.unary) return factor_log;
    NbpSummary& summary = result_.summary;
    const auto unary_start = Clock::now();
    node.unary->evaluate(batch, &unary_values_);
    summary.time_unary += Clock::now() - unary_start;
    summary.unary_points_scored += total;
    if (unary_values_.size() != total)
      throw std::logic_error("pointwise unary returned the wrong number of values");
    factor_log += unary_values_;
    return factor_log;
  }

  // Then the pointwise pairwise factors. Each one's values on the belief's samples are kept in
  // belief->factor_logs, so that the neighbour can divide them out.
  void add_pairwise_factors(int t, const Eigen::MatrixXd& batch, std::mt19937_64& node_rng,
                            BeliefSamples* belief, Eigen::VectorXd* factor_log) {
    const std::vector<Incidence>& incs = incidences_[t];
    belief->factor_logs.assign(incs.size(), Eigen::VectorXd());
    for (int k = 0; k < static_cast<int>(incs.size()); ++k) {
      if (incs[k].sampled) continue;
      const Eigen::MatrixXd& neighbour_points = neighbour_samples(incs[k], node_rng);
      mrf_.edges[incs[k].edge].potential->log_factor(
          reverse(incs[k].outgoing), batch, neighbour_points, neighbour_weights_, &factor_values_);
      *factor_log += factor_values_;
      belief->factor_logs[k] = factor_values_.tail(t_samples_);
    }
  }

  // The neighbour's samples across a pointwise edge, without the factor this node contributed
  // to them, with their weights in neighbour_weights_ (an unbiased equal-weight subsample when
  // there are more than options_.pointwise_neighbour_samples, so the factor stays O(M)).
  const Eigen::MatrixXd& neighbour_samples(const Incidence& inc, std::mt19937_64& node_rng) {
    const BeliefSamples& other = beliefs_[inc.neighbour];
    int back = -1;
    const auto& other_incs = incidences_[inc.neighbour];
    for (int j = 0; j < static_cast<int>(other_incs.size()); ++j)
      if (other_incs[j].edge == inc.edge) back = j;
    Eigen::VectorXd other_log = other.log_weights;
    if (back >= 0 && other.factor_logs[back].size() == other_log.size())
      other_log -= other.factor_logs[back];
    normalise_log_weights(other_log, &neighbour_weights_);
    if (neighbour_weights_.size() <= options_.pointwise_neighbour_samples) return other.points;
    const std::vector<int> picked =
        systematic_resample(neighbour_weights_, options_.pointwise_neighbour_samples, node_rng);
    subsample_.resize(d_, static_cast<Eigen::Index>(picked.size()));
    for (size_t j = 0; j < picked.size(); ++j) subsample_.col(j) = other.points.col(picked[j]);
    neighbour_weights_.setConstant(picked.size(), 1.0 / picked.size());
    return subsample_;
  }

  // Adaptive tempering: the pointwise factors enter the weights raised to beta, the largest
  // exponent <= 1 that keeps the belief's effective sample size above the set fraction.
  void temper(int t, const Eigen::VectorXd& factor_log, Eigen::VectorXd* log_weights,
              BeliefSamples* belief) {
    double beta = 1.0;
    if (options_.min_effective_sample_fraction > 0)
      beta = tempering_exponent(log_weights->tail(t_samples_), factor_log.tail(t_samples_),
                                options_.min_effective_sample_fraction);
    for (Eigen::Index i = 0; i < log_weights->size(); ++i)
      if (beta > 0 || std::isfinite(factor_log[i])) (*log_weights)[i] += beta * factor_log[i];
    for (Eigen::VectorXd& logs : belief->factor_logs)
      if (logs.size() > 0)
        logs = beta > 0 ? Eigen::VectorXd(beta * logs) : Eigen::VectorXd::Zero(logs.size());
    temperatures_[t] = beta;
  }

  // 3. Normalises each task's weights and pushes its samples through the potentials: the new
  // messages, and the new belief.
  void send(int t, const std::vector<Task>& tasks, const Eigen::MatrixXd& batch,
            const Eigen::VectorXd& log_weights, bool messages_from_full_product,
            std::mt19937_64& node_rng, BeliefSamples* belief, double* iteration_min_ess) {
    const std::vector<Incidence>& incs = incidences_[t];
    NbpSummary& summary = result_.summary;
    Eigen::VectorXd weights, message_weights;
    for (const Task& task : tasks) {
      const Eigen::VectorXd task_log = log_weights.segment(task.offset, task.count);
      normalise_log_weights(task_log, &weights);
      const double ess = effective_sample_size(weights);
      summary.min_effective_sample_size = std::min(summary.min_effective_sample_size, ess);
      const Eigen::MatrixXd points = batch.middleCols(task.offset, task.count);
      if (messages_from_full_product && task.count == m_ && task.exclude < 0) {
        // Every outgoing message from the full product: dividing by the receiver's message
        // leaves the product without it as the target.
        for (const Incidence& inc : incs) {
          if (!inc.sampled || mrf_.nodes[inc.neighbour].fixed) continue;
          const GaussianMixture& incoming = messages_[inc.edge][slot(reverse(inc.outgoing))];
          normalise_log_weights(task_log - log_evaluate(incoming, points), &message_weights);
          summary.min_effective_sample_size =
              std::min(summary.min_effective_sample_size, effective_sample_size(message_weights));
          next_messages_[inc.edge][slot(inc.outgoing)] =
              push(mrf_.edges[inc.edge], inc.outgoing, points, message_weights, node_rng);
        }
      }
      if (task.exclude >= 0) {
        const Incidence& inc = incs[task.exclude];
        next_messages_[inc.edge][slot(inc.outgoing)] =
            push(mrf_.edges[inc.edge], inc.outgoing, points, weights, node_rng);
      } else if (task.exclude == -1) {
        *iteration_min_ess = std::min(*iteration_min_ess, ess);
        belief->points = points;
        belief->log_weights = weights.array().log();
        for (int k = 0; k < static_cast<int>(incs.size()); ++k)
          if (belief->factor_logs[k].size() == 0)
            belief->factor_logs[k] = Eigen::VectorXd::Zero(task.count);
      }
    }
  }

  // Synchronous schedule: the new messages replace the old ones together; then the beliefs
  // as mixtures (history, and the result after the last iteration).
  void finish_iteration(int iteration, double iteration_min_ess) {
    for (size_t e = 0; e < messages_.size(); ++e)
      for (int s = 0; s < 2; ++s)
        if (next_messages_[e][s].size() > 0) messages_[e][s] = std::move(next_messages_[e][s]);
    std::swap(beliefs_, next_beliefs_);
    NbpSummary& summary = result_.summary;
    summary.iterations_run = iteration + 1;
    summary.final_min_effective_sample_size = iteration_min_ess;
    const bool last = iteration + 1 == options_.iterations;
    if (!options_.keep_history && !last) return;
    std::vector<GaussianMixture> snapshot(n_);
    for (int t = 0; t < n_; ++t) {
      GaussianMixture& g = snapshot[t];
      g.means = beliefs_[t].points;
      normalise_log_weights(beliefs_[t].log_weights, &g.weights);
      g.variances =
          mrf_.nodes[t].fixed
              ? Eigen::MatrixXd(Eigen::VectorXd::Constant(d_, options_.min_bandwidth_variance))
              : Eigen::MatrixXd(
                    rule_of_thumb_bandwidth(g.means, g.weights, options_.min_bandwidth_variance));
    }
    if (options_.keep_history) result_.history.push_back(snapshot);
    if (last) {
      result_.beliefs = std::move(snapshot);
      result_.temperatures = temperatures_;
    }
  }

  const PairwiseMrf& mrf_;
  const NbpOptions& options_;
  std::mt19937_64& rng_;
  const int n_, d_, m_, t_samples_;
  const bool from_belief_;
  ProductOptions product_options_;
  NbpResult result_;
  std::vector<std::vector<Incidence>> incidences_;
  // messages_[e][slot(direction)]: the latest message along that direction (sampled edges).
  std::vector<std::array<GaussianMixture, 2>> messages_;
  std::vector<BeliefSamples> beliefs_;
  std::vector<std::array<GaussianMixture, 2>> next_messages_;
  std::vector<BeliefSamples> next_beliefs_;
  std::vector<double> temperatures_;
  // Scratch buffers reused across nodes and iterations.
  Eigen::VectorXd unary_values_, factor_values_, neighbour_weights_;
  Eigen::MatrixXd subsample_;
};

}  // namespace

NbpResult run_nbp(const PairwiseMrf& mrf, const NbpOptions& options, std::mt19937_64& rng) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("NBP options: " + why);
  if (!mrf.IsValid(&why)) throw std::invalid_argument("NBP graph: " + why);
  return NbpRun(mrf, options, rng).run();
}

}  // namespace clutterscope::estimator
