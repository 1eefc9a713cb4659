#include "clutterscope/estimator/bop_scores.hpp"

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <stdexcept>
#include <string>

namespace clutterscope::estimator {

namespace {

// numpy's pairwise summation (np.mean sums this way), so that averages agree to the last bit.
double numpy_sum(const double* values, std::size_t n) {
  if (n < 8) {
    double sum = 0.0;
    for (std::size_t i = 0; i < n; ++i) sum += values[i];
    return sum;
  }
  if (n <= 128) {
    double r[8];
    for (int j = 0; j < 8; ++j) r[j] = values[j];
    std::size_t i = 8;
    for (; i < n - n % 8; i += 8) {
      for (int j = 0; j < 8; ++j) r[j] += values[i + j];
    }
    double sum = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for (; i < n; ++i) sum += values[i];
    return sum;
  }
  std::size_t half = n / 2;
  half -= half % 8;
  return numpy_sum(values, half) + numpy_sum(values + half, n - half);
}

}  // namespace

std::vector<double> bop19_fraction_thresholds() {
  // np.arange(0.05, 0.51, 0.05): start + i * step.
  std::vector<double> thresholds;
  for (int i = 0; i < 10; ++i) thresholds.push_back(0.05 + i * 0.05);
  return thresholds;
}

std::vector<double> bop19_mspd_thresholds_px() {
  std::vector<double> thresholds;
  for (int i = 0; i < 10; ++i) thresholds.push_back(5.0 + i * 5.0);
  return thresholds;
}

std::vector<int> bop_top_estimates(const std::vector<double>& scores_in_file_order, int n_top) {
  std::vector<int> order(scores_in_file_order.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return scores_in_file_order[a] > scores_in_file_order[b]; });
  if (n_top > 0 && order.size() > static_cast<std::size_t>(n_top)) order.resize(n_top);
  return order;
}

std::vector<bool> bop_valid_gt(const std::vector<BopGtInstance>& gt,
                               const std::map<int, int>& targets, double visib_gt_min) {
  std::vector<bool> valid(gt.size(), false);
  if (visib_gt_min >= 0) {
    for (std::size_t k = 0; k < gt.size(); ++k) {
      valid[k] = targets.count(gt[k].obj_id) > 0 && gt[k].visib_fract >= visib_gt_min;
    }
    return valid;
  }
  std::vector<int> order(gt.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return gt[a].visib_fract > gt[b].visib_fract; });
  std::map<int, int> to_add = targets;
  for (const int k : order) {
    const auto left = to_add.find(gt[k].obj_id);
    if (left != to_add.end() && left->second > 0) {
      valid[k] = true;
      --left->second;
    }
  }
  return valid;
}

std::vector<int> bop_match(const std::vector<BopEstimateErrors>& estimates,
                           const std::vector<bool>& valid, double threshold, int gt_count) {
  std::vector<int> matched(gt_count, -1);
  std::vector<const BopEstimateErrors*> sorted;
  for (const BopEstimateErrors& estimate : estimates) sorted.push_back(&estimate);
  std::stable_sort(
      sorted.begin(), sorted.end(),
      [](const BopEstimateErrors* a, const BopEstimateErrors* b) { return a->score > b->score; });
  for (const BopEstimateErrors* estimate : sorted) {
    int best = -1;
    double best_error = threshold;
    for (const auto& [gt_id, error] : estimate->errors) {
      if (gt_id < 0 || gt_id >= gt_count) {
        throw std::invalid_argument("bop_match: gt index " + std::to_string(gt_id) +
                                    " out of range (" + std::to_string(gt_count) + " instances)");
      }
      const bool is_valid = valid.empty() || valid[gt_id];
      if (is_valid && matched[gt_id] < 0 && error < best_error) {
        best = gt_id;
        best_error = error;
      }
    }
    if (best >= 0) matched[best] = estimate->est_id;
  }
  return matched;
}

BopRecall bop_recall(const std::vector<BopImageErrors>& images, double threshold,
                     double visib_gt_min) {
  BopRecall result;
  result.threshold = threshold;
  for (const BopImageErrors& image : images) {
    const int gt_count = static_cast<int>(image.gt.size());
    const std::vector<bool> valid = bop_valid_gt(image.gt, image.targets, visib_gt_min);
    std::vector<int> matched(gt_count, -1);
    for (const auto& [obj_id, estimates] : image.estimates) {
      // Init-capture: a C++17 lambda cannot capture a structured binding (clang refuses it).
      const bool in_image =
          std::any_of(image.gt.begin(), image.gt.end(),
                      [id = obj_id](const BopGtInstance& g) { return g.obj_id == id; });
      if (!in_image) continue;  // match_poses_scene matches only objects of the GT
      const std::vector<int> object_matches = bop_match(estimates, valid, threshold, gt_count);
      for (int k = 0; k < gt_count; ++k) {
        if (object_matches[k] >= 0) matched[k] = object_matches[k];
      }
    }
    result.gt_count += gt_count;
    for (int k = 0; k < gt_count; ++k) {
      if (!valid[k]) continue;
      ++result.targets_count;
      if (matched[k] >= 0) ++result.tp_count;
    }
  }
  result.recall =
      result.targets_count == 0 ? 0.0 : result.tp_count / static_cast<double>(result.targets_count);
  return result;
}

double bop_mean(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  return numpy_sum(values.data(), values.size()) / static_cast<double>(values.size());
}

double bop_average_recall(const std::vector<BopRecall>& recalls) {
  std::vector<double> values;
  for (const BopRecall& recall : recalls) values.push_back(recall.recall);
  return bop_mean(values);
}

}  // namespace clutterscope::estimator
