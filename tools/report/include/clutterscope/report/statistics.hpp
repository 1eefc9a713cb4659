#pragma once

// Statistics of a clutter report: correlations with bootstrap intervals and the table by
// visibility band. Pure functions. A statistic that is not defined for its input (fewer than
// three objects, a constant column, an empty band) is an explicit undefined value carrying
// the reason; it is written as null plus the reason, never as NaN.

#include <clutterscope/report/tables.hpp>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace clutterscope::report {

// A number, or the reason why it is undefined for this input.
struct Statistic {
  std::optional<double> value;
  std::string undefined_reason;  // empty iff value is set

  static Statistic of(double value);
  static Statistic undefined(std::string reason);
  bool defined() const { return value.has_value(); }
};

// Fewest pairs a correlation is computed from.
constexpr int kMinCorrelationPairs = 3;

// Pearson's r. Undefined for mismatched lengths, fewer than 3 pairs or a constant column.
Statistic pearson(const std::vector<double>& x, const std::vector<double>& y);

// Ranks 1..n, tied values sharing the average of their ranks ([10, 20, 20, 30] -> 1, 2.5,
// 2.5, 4).
std::vector<double> average_ranks(const std::vector<double>& values);

// Spearman's rho: Pearson's r of the average ranks (the tie-corrected form). Undefined as
// pearson(), a column whose values are all tied being constant.
Statistic spearman(const std::vector<double>& x, const std::vector<double>& y);

// Median (mean of the two middle values for an even count); undefined when empty.
Statistic median(std::vector<double> values);
Statistic mean(const std::vector<double>& values);
// Quantile with linear interpolation between order statistics (type 7, as numpy's default).
Statistic quantile(std::vector<double> values, double probability);

enum class CorrelationKind { kPearson, kSpearman };
const char* to_string(CorrelationKind kind);

struct BootstrapOptions {
  int resamples = 2000;
  // Work cap for large tables: at most this many pair draws per interval, so the resample
  // count drops (never below kMinBootstrapResamples) once n * resamples exceeds it. With
  // hundreds of thousands of objects the interval is narrow and a few hundred resamples
  // resolve it.
  long long max_draws = 100'000'000;
  double confidence = 0.95;
  bool IsValid(std::string* why) const;
};

struct Interval {
  double low = 0.0;
  double high = 0.0;
};

struct CorrelationWithInterval {
  CorrelationKind kind = CorrelationKind::kSpearman;
  int n = 0;           // pairs used
  Statistic estimate;  // on the full sample
  std::optional<Interval> interval;
  std::string interval_undefined_reason;  // empty iff interval is set
  int resamples_used = 0;                 // after the max_draws cap
  int resamples_defined = 0;              // resamples whose correlation was defined
};

constexpr int kMinBootstrapResamples = 200;

// Resamples drawn for n pairs: options.resamples, capped by max_draws / n but at least
// kMinBootstrapResamples (or options.resamples when that is smaller).
int bootstrap_resamples(const BootstrapOptions& options, size_t n);

// The correlation and its bootstrap percentile interval: bootstrap_resamples() resamples of the
// pairs with replacement, drawn from `rng` (deterministic for a given seed and input), the interval
// being the (1 - confidence)/2 and (1 + confidence)/2 quantiles of the resampled correlations.
// Resamples where the correlation is undefined (all draws tied) are left out; the interval is
// undefined when the estimate is, or fewer than 90% of resamples are defined.
CorrelationWithInterval bootstrap_correlation(const std::vector<double>& x,
                                              const std::vector<double>& y, CorrelationKind kind,
                                              const BootstrapOptions& options,
                                              std::mt19937_64& rng);

// Correlations of one quantity against visibility.
struct CorrelationPair {
  std::string quantity;  // e.g. "log10_max_variance_cm2"
  int excluded = 0;      // objects left out (no estimate; for the error also no GT error)
  int floored = 0;       // variance only: objects counted at kLogVarianceFloorCm2
  CorrelationWithInterval pearson;
  CorrelationWithInterval spearman;
};

// The log-variance correlation takes log10(max(variance, this)). A fused variance is exactly 0
// when all K ICP fits end on the same point: the most certain estimates, which leaving out
// would bias the correlation. (1 um)^2 is far below any spread the estimator resolves
// (estimates.csv positions have 1 um steps, depth noise is ~1 mm), so the floor changes no
// variance that carries information.
constexpr double kLogVarianceFloorCm2 = 1e-8;

// log10(max(max-axis variance, kLogVarianceFloorCm2)) against visib_fract, over objects with
// an estimate. Pearson is drawn from `rng` first, then Spearman.
CorrelationPair variance_visibility_correlation(const std::vector<ObjectRow>& objects,
                                                const BootstrapOptions& options,
                                                std::mt19937_64& rng);
// err_cm against visib_fract, over objects with an estimate and an error.
CorrelationPair error_visibility_correlation(const std::vector<ObjectRow>& objects,
                                             const BootstrapOptions& options, std::mt19937_64& rng);

// Band b of 10 holds visibilities in [b/10, (b+1)/10); the last band also holds 1.0.
constexpr int kVisibilityBands = 10;
int visibility_band(double visib_fract);

struct VisibilityBand {
  double visibility_min = 0.0;
  double visibility_max = 0.0;
  int count = 0;      // objects in the band
  int estimated = 0;  // of those, with an estimate
  int confident = 0;  // estimates with max-axis variance <= threshold
  int confident_with_error = 0;
  int confident_inaccurate = 0;   // confident and err_cm > accurate_cm
  Statistic median_variance_cm2;  // max-axis variance of the estimates
  Statistic mean_variance_cm2;
  Statistic median_error_cm;
  Statistic confident_share;             // confident / estimated
  Statistic confident_inaccurate_share;  // confident_inaccurate / confident_with_error
};

// "Confident" is max-axis variance <= variance_threshold_cm2 (recomputed from the variances
// so the table follows the report's threshold), "inaccurate" is err_cm > accurate_cm.
std::vector<VisibilityBand> visibility_bands(const std::vector<ObjectRow>& objects,
                                             double variance_threshold_cm2, double accurate_cm);

}  // namespace clutterscope::report
