#include <unistd.h>

#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/progress.hpp>
#include <cstdio>
#include <iostream>

namespace clutterscope::batch {

namespace {
constexpr auto kRedrawInterval = std::chrono::milliseconds(100);
constexpr int kBarWidth = 28;
}  // namespace

Progress::Progress(std::string label, std::size_t total, std::size_t already_done, Style style,
                   std::string unit)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      already_done_(already_done),
      style_(style),
      start_(std::chrono::steady_clock::now()) {
  if (style_ == Style::kAuto) {
    style_ = ::isatty(STDERR_FILENO) ? Style::kBar : Style::kSummaryOnly;
  }
  last_draw_ = start_ - kRedrawInterval;
  std::lock_guard<std::mutex> lock(mutex_);
  draw_locked(true);
}

double Progress::elapsed_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

std::string Progress::format_duration(double seconds) {
  if (!(seconds >= 0) || seconds > 1e8) return "--:--";
  const long total = static_cast<long>(seconds + 0.5);
  const long hours = total / 3600, minutes = (total / 60) % 60, secs = total % 60;
  char buffer[48];
  if (hours > 0) {
    std::snprintf(buffer, sizeof(buffer), "%ld:%02ld:%02ld", hours, minutes, secs);
  } else {
    std::snprintf(buffer, sizeof(buffer), "%ld:%02ld", minutes, secs);
  }
  return buffer;
}

void Progress::item_done(bool ok) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++computed_;
  if (!ok) ++failed_;
  draw_locked(false);
}

void Progress::draw_locked(bool force) {
  if (style_ != Style::kBar) return;
  const auto now = std::chrono::steady_clock::now();
  if (!force && now - last_draw_ < kRedrawInterval) return;
  last_draw_ = now;
  const std::size_t done = already_done_ + computed_;
  const double fraction = total_ == 0 ? 1.0 : static_cast<double>(done) / total_;
  const int filled = static_cast<int>(fraction * kBarWidth);
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? computed_ / elapsed : 0.0;
  const std::size_t remaining = total_ - done;
  const std::string eta =
      rate > 0 ? format_duration(remaining / rate) : (remaining == 0 ? "0:00" : "--:--");
  std::string line = "\r" + label_ + " [" + std::string(filled, '#') +
                     std::string(kBarWidth - filled, '.') + "] " + std::to_string(done) + "/" +
                     std::to_string(total_) + "  " + format_fixed(rate, 1) + " " + unit_ +
                     "/s  ETA " + eta + "\x1b[K";
  std::cerr << line << std::flush;
  drawn_ = true;
}

void Progress::finish(std::size_t failed) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (style_ == Style::kQuiet) return;
  if (drawn_) std::cerr << "\r\x1b[K";
  const double elapsed = elapsed_seconds();
  const double rate = elapsed > 0 ? computed_ / elapsed : 0.0;
  // "1/1 image", not "1/1 images"; the units are plural nouns ("images", "scenes").
  const bool one = total_ == 1 && !unit_.empty() && unit_.back() == 's';
  std::cerr << label_ << ": " << already_done_ + computed_ << "/" << total_ << " "
            << (one ? unit_.substr(0, unit_.size() - 1) : unit_) << " (" << computed_ - failed_
            << " computed, " << already_done_ << " resumed, " << failed << " failed) in "
            << seconds_text(elapsed) << ", " << format_fixed(rate, 1) << " " << unit_ << "/s\n"
            << std::flush;
}

}  // namespace clutterscope::batch
