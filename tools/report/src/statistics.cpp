#include <algorithm>
#include <clutterscope/batch/quantile.hpp>
#include <clutterscope/report/statistics.hpp>
#include <cmath>
#include <numeric>

namespace clutterscope::report {

namespace {

// Fewer defined resamples than this share make the interval undefined: the bootstrap
// distribution would be conditioned on the rare non-degenerate draws.
constexpr double kMinDefinedResampleShare = 0.9;

bool is_constant(const std::vector<double>& values) {
  return std::all_of(values.begin(), values.end(),
                     [&](double value) { return value == values.front(); });
}

Statistic correlation(const std::vector<double>& x, const std::vector<double>& y,
                      CorrelationKind kind) {
  return kind == CorrelationKind::kPearson ? pearson(x, y) : spearman(x, y);
}

std::string count_text(int n) { return std::to_string(n); }

}  // namespace

Statistic Statistic::of(double value) {
  Statistic statistic;
  statistic.value = value;
  return statistic;
}

Statistic Statistic::undefined(std::string reason) {
  Statistic statistic;
  statistic.undefined_reason = std::move(reason);
  return statistic;
}

Statistic pearson(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size()) {
    return Statistic::undefined("columns differ in length (" + count_text(x.size()) + " vs " +
                                count_text(y.size()) + ")");
  }
  const int n = static_cast<int>(x.size());
  if (n < kMinCorrelationPairs) {
    return Statistic::undefined("fewer than " + count_text(kMinCorrelationPairs) + " objects (" +
                                count_text(n) + ")");
  }
  if (is_constant(x)) return Statistic::undefined("first column is constant");
  if (is_constant(y)) return Statistic::undefined("second column is constant");
  const double mean_x = std::accumulate(x.begin(), x.end(), 0.0) / n;
  const double mean_y = std::accumulate(y.begin(), y.end(), 0.0) / n;
  double sxy = 0.0, sxx = 0.0, syy = 0.0;
  for (int i = 0; i < n; ++i) {
    const double dx = x[i] - mean_x;
    const double dy = y[i] - mean_y;
    sxy += dx * dy;
    sxx += dx * dx;
    syy += dy * dy;
  }
  // Rounding can push |r| a hair above 1 for exactly collinear data.
  return Statistic::of(std::clamp(sxy / std::sqrt(sxx * syy), -1.0, 1.0));
}

std::vector<double> average_ranks(const std::vector<double>& values) {
  const size_t n = values.size();
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return values[a] < values[b]; });
  std::vector<double> ranks(n);
  for (size_t start = 0; start < n;) {
    size_t end = start + 1;
    while (end < n && values[order[end]] == values[order[start]]) ++end;
    // Ranks start+1 .. end share their average.
    const double rank = 0.5 * static_cast<double>(start + 1 + end);
    for (size_t k = start; k < end; ++k) ranks[order[k]] = rank;
    start = end;
  }
  return ranks;
}

Statistic spearman(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size() || static_cast<int>(x.size()) < kMinCorrelationPairs) {
    return pearson(x, y);  // same reasons
  }
  if (is_constant(x)) return Statistic::undefined("first column is constant");
  if (is_constant(y)) return Statistic::undefined("second column is constant");
  return pearson(average_ranks(x), average_ranks(y));
}

Statistic median(std::vector<double> values) { return quantile(std::move(values), 0.5); }

Statistic mean(const std::vector<double>& values) {
  if (values.empty()) return Statistic::undefined("no values");
  return Statistic::of(std::accumulate(values.begin(), values.end(), 0.0) /
                       static_cast<double>(values.size()));
}

Statistic quantile(std::vector<double> values, double probability) {
  if (values.empty()) return Statistic::undefined("no values");
  return Statistic::of(batch::linear_quantile(std::move(values), probability));
}

const char* to_string(CorrelationKind kind) {
  return kind == CorrelationKind::kPearson ? "pearson" : "spearman";
}

bool BootstrapOptions::IsValid(std::string* why) const {
  if (resamples < 100) {
    *why = "bootstrap resamples must be >= 100, got " + std::to_string(resamples);
    return false;
  }
  if (!(confidence > 0.0 && confidence < 1.0)) {
    *why = "bootstrap confidence must be in (0, 1), got " + std::to_string(confidence);
    return false;
  }
  if (max_draws < 1) {
    *why = "bootstrap max_draws must be >= 1, got " + std::to_string(max_draws);
    return false;
  }
  return true;
}

int bootstrap_resamples(const BootstrapOptions& options, size_t n) {
  const long long affordable = options.max_draws / static_cast<long long>(std::max<size_t>(n, 1));
  const long long minimum = std::min<long long>(options.resamples, kMinBootstrapResamples);
  return static_cast<int>(std::max(minimum, std::min<long long>(options.resamples, affordable)));
}

CorrelationWithInterval bootstrap_correlation(const std::vector<double>& x,
                                              const std::vector<double>& y, CorrelationKind kind,
                                              const BootstrapOptions& options,
                                              std::mt19937_64& rng) {
  CorrelationWithInterval result;
  result.kind = kind;
  result.n = static_cast<int>(std::min(x.size(), y.size()));
  result.estimate = correlation(x, y, kind);
  if (!result.estimate.defined()) {
    result.interval_undefined_reason = result.estimate.undefined_reason;
    return result;
  }
  const size_t n = x.size();
  std::vector<double> resampled;
  result.resamples_used = bootstrap_resamples(options, n);
  resampled.reserve(result.resamples_used);
  std::vector<double> rx(n), ry(n);
  for (int r = 0; r < result.resamples_used; ++r) {
    for (size_t i = 0; i < n; ++i) {
      // Plain modulo rather than std::uniform_int_distribution, whose algorithm differs
      // between standard libraries: the same seed gives the same interval everywhere. The
      // modulo bias is below n / 2^64.
      const size_t pick = static_cast<size_t>(rng() % n);
      rx[i] = x[pick];
      ry[i] = y[pick];
    }
    const Statistic value = correlation(rx, ry, kind);
    if (value.defined()) resampled.push_back(*value.value);
  }
  result.resamples_defined = static_cast<int>(resampled.size());
  if (result.resamples_defined < kMinDefinedResampleShare * result.resamples_used) {
    result.interval_undefined_reason = "only " + std::to_string(result.resamples_defined) + " of " +
                                       std::to_string(result.resamples_used) +
                                       " bootstrap resamples have a defined correlation";
    return result;
  }
  const double tail = 0.5 * (1.0 - options.confidence);
  result.interval =
      Interval{*quantile(resampled, tail).value, *quantile(resampled, 1.0 - tail).value};
  return result;
}

namespace {

CorrelationPair correlate_with_visibility(std::string quantity, const std::vector<double>& values,
                                          const std::vector<double>& visibilities, int excluded,
                                          const BootstrapOptions& options, std::mt19937_64& rng) {
  CorrelationPair pair;
  pair.quantity = std::move(quantity);
  pair.excluded = excluded;
  pair.pearson =
      bootstrap_correlation(values, visibilities, CorrelationKind::kPearson, options, rng);
  pair.spearman =
      bootstrap_correlation(values, visibilities, CorrelationKind::kSpearman, options, rng);
  return pair;
}

}  // namespace

CorrelationPair variance_visibility_correlation(const std::vector<ObjectRow>& objects,
                                                const BootstrapOptions& options,
                                                std::mt19937_64& rng) {
  std::vector<double> log_variance, visibility;
  int floored = 0;
  for (const ObjectRow& object : objects) {
    if (!object.estimate) continue;
    const double variance = object.estimate->max_variance_cm2();
    floored += variance < kLogVarianceFloorCm2;
    log_variance.push_back(std::log10(std::max(variance, kLogVarianceFloorCm2)));
    visibility.push_back(object.visib_fract);
  }
  const int excluded = static_cast<int>(objects.size() - log_variance.size());
  CorrelationPair pair = correlate_with_visibility("log10_max_variance_cm2", log_variance,
                                                   visibility, excluded, options, rng);
  pair.floored = floored;
  return pair;
}

CorrelationPair error_visibility_correlation(const std::vector<ObjectRow>& objects,
                                             const BootstrapOptions& options,
                                             std::mt19937_64& rng) {
  std::vector<double> error, visibility;
  for (const ObjectRow& object : objects) {
    if (!object.estimate || !object.estimate->err_cm) continue;
    error.push_back(*object.estimate->err_cm);
    visibility.push_back(object.visib_fract);
  }
  const int excluded = static_cast<int>(objects.size() - error.size());
  return correlate_with_visibility("err_cm", error, visibility, excluded, options, rng);
}

int visibility_band(double visib_fract) {
  // The small epsilon keeps 0.3 (stored as 0.29999...) in band 3, as a reader expects.
  const int band = static_cast<int>(std::floor(visib_fract * kVisibilityBands + 1e-9));
  return std::clamp(band, 0, kVisibilityBands - 1);
}

std::vector<VisibilityBand> visibility_bands(const std::vector<ObjectRow>& objects,
                                             double variance_threshold_cm2, double accurate_cm) {
  std::vector<VisibilityBand> bands(kVisibilityBands);
  std::vector<std::vector<double>> variances(kVisibilityBands), errors(kVisibilityBands);
  for (int b = 0; b < kVisibilityBands; ++b) {
    bands[b].visibility_min = static_cast<double>(b) / kVisibilityBands;
    bands[b].visibility_max = static_cast<double>(b + 1) / kVisibilityBands;
  }
  for (const ObjectRow& object : objects) {
    const int b = visibility_band(object.visib_fract);
    VisibilityBand& band = bands[b];
    ++band.count;
    if (!object.estimate) continue;
    const PoseEstimate& estimate = *object.estimate;
    ++band.estimated;
    variances[b].push_back(estimate.max_variance_cm2());
    if (estimate.err_cm) errors[b].push_back(*estimate.err_cm);
    if (!estimate.confident_at(variance_threshold_cm2)) continue;
    ++band.confident;
    if (!estimate.err_cm) continue;
    ++band.confident_with_error;
    if (*estimate.err_cm > accurate_cm) ++band.confident_inaccurate;
  }
  for (int b = 0; b < kVisibilityBands; ++b) {
    VisibilityBand& band = bands[b];
    const std::string none_estimated = "no estimated objects in this band";
    band.median_variance_cm2 =
        band.estimated ? median(variances[b]) : Statistic::undefined(none_estimated);
    band.mean_variance_cm2 =
        band.estimated ? mean(variances[b]) : Statistic::undefined(none_estimated);
    band.median_error_cm = errors[b].empty()
                               ? Statistic::undefined("no estimates with an error in this band")
                               : median(errors[b]);
    band.confident_share = band.estimated
                               ? Statistic::of(static_cast<double>(band.confident) / band.estimated)
                               : Statistic::undefined(none_estimated);
    band.confident_inaccurate_share =
        band.confident_with_error
            ? Statistic::of(static_cast<double>(band.confident_inaccurate) /
                            band.confident_with_error)
            : Statistic::undefined("no confident estimates with an error in this band");
  }
  return bands;
}

}  // namespace clutterscope::report
