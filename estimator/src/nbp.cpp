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

NbpResult run_nbp(const PairwiseMrf& mrf, const NbpOptions& options, std::mt19937_64& rng) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("NBP options: " + why);
  if (!mrf.IsValid(&why)) throw std::invalid_argument("NBP graph: " + why);
  const auto start = Clock::now();
  const int n = static_cast<int>(mrf.nodes.size());
  const int d = mrf.dimension;
  const int m = options.particles;
  const int t_samples = options.belief_samples > 0 ? options.belief_samples : m;
  const bool from_belief = options.message_proposal == MessageProposal::kBeliefImportance;
  ProductOptions product_options;
  product_options.method = options.product_method;
  product_options.gibbs_sweeps = options.gibbs_sweeps;
  NbpResult result;
  NbpSummary& summary = result.summary;
  summary.min_effective_sample_size = std::numeric_limits<double>::infinity();

  std::vector<std::vector<Incidence>> incidences(n);
  for (int e = 0; e < static_cast<int>(mrf.edges.size()); ++e) {
    const MrfEdge& edge = mrf.edges[e];
    const bool sampled = edge.potential->is_sampled();
    incidences[edge.first].push_back({e, edge.second, EdgeDirection::kFirstToSecond, sampled});
    incidences[edge.second].push_back({e, edge.first, EdgeDirection::kSecondToFirst, sampled});
  }
  // Pushes weighted samples of the sender through the edge potential into a message mixture.
  auto push = [&](const MrfEdge& edge, EdgeDirection direction, const Eigen::MatrixXd& points,
                  const Eigen::VectorXd& weights, std::mt19937_64& node_rng) {
    GaussianMixture message;
    Eigen::VectorXd offset, variance;
    if (options.message_bandwidth == MessageBandwidth::kPotentialKernel &&
        edge.potential->gaussian_kernel(direction, &offset, &variance)) {
      message.means = points.colwise() + offset;
      message.variances = variance;
    } else {
      edge.potential->sample(direction, points, node_rng, &message.means);
      message.variances =
          rule_of_thumb_bandwidth(message.means, weights, options.min_bandwidth_variance);
    }
    message.weights = weights;
    return message;
  };

  // messages[e][slot(direction)]: the latest message along that direction (sampled edges).
  std::vector<std::array<GaussianMixture, 2>> messages(mrf.edges.size());
  std::vector<BeliefSamples> beliefs(n);
  for (int t = 0; t < n; ++t) {
    const MrfNode& node = mrf.nodes[t];
    BeliefSamples& b = beliefs[t];
    if (node.fixed) {
      b.points = node.fixed_position;
      b.log_weights = Eigen::VectorXd::Zero(1);
    } else {
      b.points = sample_mixture(node.initial, t_samples, rng);
      b.log_weights = Eigen::VectorXd::Constant(t_samples, -std::log(double(t_samples)));
    }
    b.factor_logs.assign(incidences[t].size(), Eigen::VectorXd::Zero(b.points.cols()));
    // Messages m^0 from the initial mixtures, and the constant messages of fixed nodes.
    for (const Incidence& inc : incidences[t]) {
      if (!inc.sampled || mrf.nodes[inc.neighbour].fixed) continue;
      const MrfEdge& edge = mrf.edges[inc.edge];
      Eigen::VectorXd offset, variance;
      if (node.fixed && options.message_bandwidth == MessageBandwidth::kPotentialKernel &&
          edge.potential->gaussian_kernel(inc.outgoing, &offset, &variance)) {
        messages[inc.edge][slot(inc.outgoing)] =
            push(edge, inc.outgoing, node.fixed_position, Eigen::VectorXd::Ones(1), rng);
      } else {
        const Eigen::MatrixXd from = node.fixed
                                         ? Eigen::MatrixXd(node.fixed_position.replicate(1, m))
                                         : sample_mixture(node.initial, m, rng);
        messages[inc.edge][slot(inc.outgoing)] =
            push(edge, inc.outgoing, from, Eigen::VectorXd::Constant(m, 1.0 / m), rng);
      }
    }
  }

  std::vector<std::array<GaussianMixture, 2>> next_messages(mrf.edges.size());
  std::vector<BeliefSamples> next_beliefs(n);
  std::vector<uint64_t> seeds(n);
  std::vector<double> temperatures(n, 1.0);
  Eigen::VectorXd unary_values, factor_values, neighbour_weights;
  Eigen::MatrixXd subsample;
  for (int iteration = 0; iteration < options.iterations; ++iteration) {
    for (int t = 0; t < n; ++t) seeds[t] = rng();
    double iteration_min_ess = std::numeric_limits<double>::infinity();
    for (int t = 0; t < n; ++t) {
      const MrfNode& node = mrf.nodes[t];
      if (node.fixed) {
        next_beliefs[t] = beliefs[t];
        continue;
      }
      std::mt19937_64 node_rng(seeds[t]);
      const std::vector<Incidence>& incs = incidences[t];
      // 1. Products: one per outgoing sampled message to a hidden node, plus the belief.
      // With kBeliefImportance, a message whose product without the receiver would be empty
      // keeps the initial-mixture proposal: the belief would only add the receiver's message,
      // and dividing it out leaves weights that depend on how well it covers the pointwise
      // unary.
      int sampled_inputs = node.unary_mixture ? 1 : 0;
      for (const Incidence& inc : incs) sampled_inputs += inc.sampled ? 1 : 0;
      const bool messages_from_belief = from_belief && sampled_inputs > 1;
      std::vector<Task> tasks;
      bool sends = false;
      for (int k = 0; k < static_cast<int>(incs.size()); ++k) {
        if (!incs[k].sampled || mrf.nodes[incs[k].neighbour].fixed) continue;
        sends = true;
        if (!messages_from_belief) tasks.push_back({k, m});
      }
      if (messages_from_belief && sends && t_samples != m) tasks.push_back({kAllInputs, m});
      tasks.push_back({-1, t_samples});  // last: factor_logs keep the batch's tail
      int total = 0;
      for (Task& task : tasks) {
        task.offset = total;
        total += task.count;
      }
      Eigen::MatrixXd batch(d, total);
      Eigen::VectorXd log_weights = Eigen::VectorXd::Zero(total);
      auto product_start = Clock::now();
      for (Task& task : tasks) {
        MixtureList inputs;
        if (node.unary_mixture) inputs.push_back(&*node.unary_mixture);
        for (int k = 0; k < static_cast<int>(incs.size()); ++k)
          if (incs[k].sampled && k != task.exclude)
            inputs.push_back(&messages[incs[k].edge][slot(reverse(incs[k].outgoing))]);
        auto block = batch.middleCols(task.offset, task.count);
        if (task.exclude == -1 && options.adaptive_belief_proposal && iteration > 0) {
          // Previous belief as a kernel density, mixed with the initial mixture and the
          // incoming messages; weights: product of the inputs / proposal.
          GaussianMixture proposal;
          proposal.means.resize(d, 0);
          GaussianMixture previous;
          previous.means = beliefs[t].points;
          normalise_log_weights(beliefs[t].log_weights, &previous.weights);
          previous.variances = rule_of_thumb_bandwidth(previous.means, previous.weights,
                                                       options.proposal_min_variance);
          const int message_count = static_cast<int>(inputs.size()) - (node.unary_mixture ? 1 : 0);
          const double defensive = options.defensive_fraction;
          append_components(previous, 1 - defensive, &proposal);
          append_components(node.initial, message_count > 0 ? defensive / 2 : defensive, &proposal);
          for (std::size_t j = node.unary_mixture ? 1 : 0; j < inputs.size(); ++j)
            append_components(*inputs[j], defensive / 2 / message_count, &proposal);
          proposal.weights /= proposal.weights.sum();
          block = sample_mixture(proposal, task.count, node_rng);
          Eigen::VectorXd log_target = Eigen::VectorXd::Zero(task.count);
          for (const GaussianMixture* input : inputs) log_target += log_evaluate(*input, block);
          log_weights.segment(task.offset, task.count) = log_target - log_evaluate(proposal, block);
        } else if (inputs.empty()) {
          task.from_initial = true;
          block = sample_mixture(node.initial, task.count, node_rng);
          log_weights.segment(task.offset, task.count) = -log_evaluate(node.initial, block);
        } else {
          block = sample_product(inputs, task.count, product_options, node_rng);
        }
        ++summary.products_sampled;
      }
      summary.time_products += Clock::now() - product_start;
      // 2. Pointwise unary for the whole batch, then pointwise pairwise factors, summed in
      // factor_log (tempered below); log_weights keeps the proposal corrections.
      Eigen::VectorXd factor_log = Eigen::VectorXd::Zero(total);
      if (node.unary) {
        const auto unary_start = Clock::now();
        node.unary->evaluate(batch, &unary_values);
        summary.time_unary += Clock::now() - unary_start;
        summary.unary_points_scored += total;
        if (unary_values.size() != total)
          throw std::logic_error("pointwise unary returned the wrong number of values");
        factor_log += unary_values;
      }
      const auto pairwise_start = Clock::now();
      BeliefSamples& belief = next_beliefs[t];
      belief.factor_logs.assign(incs.size(), Eigen::VectorXd());
      for (int k = 0; k < static_cast<int>(incs.size()); ++k) {
        if (incs[k].sampled) continue;
        const BeliefSamples& other = beliefs[incs[k].neighbour];
        // The neighbour's samples without the factor t contributed to them.
        int back = -1;
        const auto& other_incs = incidences[incs[k].neighbour];
        for (int j = 0; j < static_cast<int>(other_incs.size()); ++j)
          if (other_incs[j].edge == incs[k].edge) back = j;
        Eigen::VectorXd other_log = other.log_weights;
        if (back >= 0 && other.factor_logs[back].size() == other_log.size())
          other_log -= other.factor_logs[back];
        normalise_log_weights(other_log, &neighbour_weights);
        const Eigen::MatrixXd* neighbour_points = &other.points;
        if (neighbour_weights.size() > options.pointwise_neighbour_samples) {
          // An unbiased equal-weight subsample keeps the factor O(M) per point.
          const std::vector<int> picked =
              systematic_resample(neighbour_weights, options.pointwise_neighbour_samples, node_rng);
          subsample.resize(d, static_cast<Eigen::Index>(picked.size()));
          for (size_t j = 0; j < picked.size(); ++j) subsample.col(j) = other.points.col(picked[j]);
          neighbour_points = &subsample;
          neighbour_weights.setConstant(picked.size(), 1.0 / picked.size());
        }
        mrf.edges[incs[k].edge].potential->log_factor(
            reverse(incs[k].outgoing), batch, *neighbour_points, neighbour_weights, &factor_values);
        factor_log += factor_values;
        belief.factor_logs[k] = factor_values.tail(t_samples);
      }
      double beta = 1.0;
      if (options.min_effective_sample_fraction > 0)
        beta = tempering_exponent(log_weights.tail(t_samples), factor_log.tail(t_samples),
                                  options.min_effective_sample_fraction);
      for (Eigen::Index i = 0; i < total; ++i)
        if (beta > 0 || std::isfinite(factor_log[i])) log_weights[i] += beta * factor_log[i];
      for (Eigen::VectorXd& logs : belief.factor_logs)
        if (logs.size() > 0)
          logs = beta > 0 ? Eigen::VectorXd(beta * logs) : Eigen::VectorXd::Zero(logs.size());
      temperatures[t] = beta;
      // 3. Normalise each task's weights and push the samples through the potentials.
      Eigen::VectorXd weights, message_weights;
      for (const Task& task : tasks) {
        const Eigen::VectorXd task_log = log_weights.segment(task.offset, task.count);
        normalise_log_weights(task_log, &weights);
        const double ess = effective_sample_size(weights);
        summary.min_effective_sample_size = std::min(summary.min_effective_sample_size, ess);
        const Eigen::MatrixXd points = batch.middleCols(task.offset, task.count);
        if (messages_from_belief && task.count == m && task.exclude < 0 && sends) {
          // Every outgoing message from the full product: dividing by the receiver's message
          // leaves the product without it as the target.
          for (const Incidence& inc : incs) {
            if (!inc.sampled || mrf.nodes[inc.neighbour].fixed) continue;
            const GaussianMixture& incoming = messages[inc.edge][slot(reverse(inc.outgoing))];
            normalise_log_weights(task_log - log_evaluate(incoming, points), &message_weights);
            summary.min_effective_sample_size =
                std::min(summary.min_effective_sample_size, effective_sample_size(message_weights));
            next_messages[inc.edge][slot(inc.outgoing)] =
                push(mrf.edges[inc.edge], inc.outgoing, points, message_weights, node_rng);
          }
        }
        if (task.exclude >= 0) {
          const Incidence& inc = incs[task.exclude];
          next_messages[inc.edge][slot(inc.outgoing)] =
              push(mrf.edges[inc.edge], inc.outgoing, points, weights, node_rng);
        } else if (task.exclude == -1) {
          iteration_min_ess = std::min(iteration_min_ess, ess);
          belief.points = points;
          belief.log_weights = weights.array().log();
          for (int k = 0; k < static_cast<int>(incs.size()); ++k)
            if (belief.factor_logs[k].size() == 0)
              belief.factor_logs[k] = Eigen::VectorXd::Zero(task.count);
        }
      }
      summary.time_pairwise += Clock::now() - pairwise_start;
    }
    // Synchronous schedule: the new messages replace the old ones together.
    for (size_t e = 0; e < messages.size(); ++e)
      for (int s = 0; s < 2; ++s)
        if (next_messages[e][s].size() > 0) messages[e][s] = std::move(next_messages[e][s]);
    std::swap(beliefs, next_beliefs);
    summary.iterations_run = iteration + 1;
    summary.final_min_effective_sample_size = iteration_min_ess;
    const bool last = iteration + 1 == options.iterations;
    if (options.keep_history || last) {
      std::vector<GaussianMixture> snapshot(n);
      for (int t = 0; t < n; ++t) {
        GaussianMixture& g = snapshot[t];
        g.means = beliefs[t].points;
        normalise_log_weights(beliefs[t].log_weights, &g.weights);
        g.variances =
            mrf.nodes[t].fixed
                ? Eigen::MatrixXd(Eigen::VectorXd::Constant(d, options.min_bandwidth_variance))
                : Eigen::MatrixXd(
                      rule_of_thumb_bandwidth(g.means, g.weights, options.min_bandwidth_variance));
      }
      if (options.keep_history) result.history.push_back(snapshot);
      if (last) {
        result.beliefs = std::move(snapshot);
        result.temperatures = temperatures;
      }
    }
  }
  if (!std::isfinite(summary.min_effective_sample_size)) summary.min_effective_sample_size = 0;
  if (!std::isfinite(summary.final_min_effective_sample_size))
    summary.final_min_effective_sample_size = 0;
  summary.time_total = Clock::now() - start;
  return result;
}

}  // namespace clutterscope::estimator
