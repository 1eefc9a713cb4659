#pragma once

// The SVG building blocks the charts and image panels share (private to the report library):
// the page margins, fixed-decimal coordinates, text elements, tick labels and axis scales.

#include <algorithm>
#include <clutterscope/report/svg.hpp>
#include <string>
#include <vector>

namespace clutterscope::report::svg::detail {

constexpr int kMarginLeft = 78;
constexpr int kMarginTop = 40;
constexpr int kMarginBottom = 56;
constexpr int kMarginRightPlain = 24;
constexpr int kSidePanelWidth = 190;  // legend and colour bar, right of the plot area
constexpr const char* kFont = "font-family=\"DejaVu Sans, Arial, sans-serif\"";

// A coordinate with two decimals ("-0.00" written as "0.00").
std::string num(double value);
// The <svg> element, its white background and its title.
std::string svg_open(int width, int height, const std::string& title);
std::string text_element(double x, double y, const std::string& text, const char* anchor,
                         const std::string& extra = "");
// `text` broken at spaces into lines of at most `max_chars` bytes (a longer word stays whole).
std::vector<std::string> wrap_words(const std::string& text, std::size_t max_chars);
// About how many characters of 12 px text fit into `pixels` (DejaVu Sans averages below 7.2 px
// a character; counting bytes over-counts non-ASCII, which only wraps earlier).
inline std::size_t chars_fitting(double pixels) {
  return static_cast<std::size_t>(std::max(1.0, pixels / 7.2));
}
// Tick label for a value: as few decimals as the tick step needs.
std::string tick_label(double value, double step);
std::string line_style(Colour colour, double width, bool dashed);

// A data range mapped onto a pixel range, linear or log10.
struct Scale {
  bool log = false;
  double lo = 0.0, hi = 1.0;  // in data units (log: positive)
  double pixel_lo = 0.0, pixel_hi = 1.0;

  double transform(double v) const { return log ? std::log10(v) : v; }
  bool drawable(double v) const { return std::isfinite(v) && (!log || v > 0.0); }
  double to_pixel(double v) const {
    const double t = (transform(v) - transform(lo)) / (transform(hi) - transform(lo));
    return pixel_lo + std::clamp(t, -0.02, 1.02) * (pixel_hi - pixel_lo);
  }
  // Tick values and the step that sets their decimals.
  std::vector<double> ticks(double* step) const {
    std::vector<double> values;
    if (log) {
      *step = 0.0;
      const int first = static_cast<int>(std::ceil(std::log10(lo) - 1e-9));
      const int last = static_cast<int>(std::floor(std::log10(hi) + 1e-9));
      const bool few_decades = last - first < 2;
      // At most about 8 labelled decades, so labels never overlap on wide ranges.
      const int decade_step = std::max(1, (last - first + 7) / 8);
      for (int e = first - 1; e <= last; ++e) {
        if ((e - first) % decade_step != 0) continue;
        for (double m : few_decades ? std::vector<double>{1, 2, 5} : std::vector<double>{1}) {
          const double v = m * std::pow(10.0, e);
          if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) values.push_back(v);
        }
      }
      return values;
    }
    const double raw = (hi - lo) / 6.0;
    const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
    double nice = magnitude;
    for (double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {
      nice = m * magnitude;
      if (nice >= raw) break;
    }
    *step = nice;
    for (double v = std::ceil(lo / nice - 1e-9) * nice; v <= hi + 1e-9 * nice; v += nice) {
      values.push_back(std::abs(v) < 1e-12 * nice ? 0.0 : v);
    }
    return values;
  }
};

// Range of the drawable values, padded (linear) or widened to whole decades (log).
Scale make_scale(const AxisSpec& axis, std::vector<double> values, bool include_zero);

}  // namespace clutterscope::report::svg::detail
