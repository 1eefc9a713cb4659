#pragma once

// Progress of a batch run on stderr. On a terminal: a bar with count, rate (items/s) and ETA,
// redrawn at most 10 times a second. Otherwise (logs, CI): nothing until the one summary line
// at the end. Quiet: nothing at all.

#include <chrono>
#include <cstddef>
#include <mutex>
#include <string>

namespace clutterscope::batch {

class Progress {
 public:
  enum class Style { kAuto, kBar, kSummaryOnly, kQuiet };

  // `total` items in this run's scope, `already_done` of them finished by an earlier run;
  // `unit` names the items in the output ("images", "scenes").
  Progress(std::string label, std::size_t total, std::size_t already_done, Style style,
           std::string unit = "images");

  // One more item done by this run, with a result (ok) or failed. Thread-safe; cheap when no
  // redraw is due.
  void item_done(bool ok = true);
  // Clears the bar and prints one line: "label: 120/120 images (99 computed, 20 resumed,
  // 1 failed) in 3.2 s, 31.4 images/s". "computed" counts the items this run computed a result
  // for (a failed one is not computed: summary.json's images_computed and run.json's computed
  // count the same); `failed` is the job's failed items. Printed unless quiet.
  void finish(std::size_t failed);

  double elapsed_seconds() const;

  // "1:05:09" / "4:09" for an ETA, for tests.
  static std::string format_duration(double seconds);

 private:
  void draw_locked(bool force);

  std::string label_;
  std::string unit_;
  std::size_t total_;
  std::size_t already_done_;
  Style style_;
  std::mutex mutex_;
  std::size_t computed_ = 0;  // items done by this run, failed ones included
  std::size_t failed_ = 0;    // of them, failed
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  bool drawn_ = false;
};

}  // namespace clutterscope::batch
