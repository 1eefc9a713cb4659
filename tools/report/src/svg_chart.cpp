// Charts with linear or log axes and horizontal bar charts.

#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/report/svg.hpp>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "svg_elements.hpp"

namespace clutterscope::report::svg {

using namespace detail;

namespace {

// Above this many points a scatter draws an evenly strided subset (noted on the chart), so a
// report over a large dataset stays a reasonably sized HTML file.
constexpr size_t kMaxScatterPoints = 20000;

}  // namespace

// The plot area of one render and the scales mapping data onto it.
struct Chart::Layout {
  int plot_left = 0, plot_right = 0, plot_top = 0, plot_bottom = 0;
  Scale sx, sy;
};

Chart::Chart(std::string title, AxisSpec x_axis, AxisSpec y_axis, int width, int height)
    : title_(std::move(title)),
      x_axis_(std::move(x_axis)),
      y_axis_(std::move(y_axis)),
      width_(width),
      height_(height) {}

void Chart::add_scatter(const std::vector<double>& x, const std::vector<double>& y,
                        const std::vector<double>& values, const ColourScale& scale) {
  if (x.size() != y.size() || x.size() != values.size()) {
    throw std::invalid_argument("scatter: x, y and colour values differ in length");
  }
  Series series;
  series.kind = Kind::kValueScatter;
  series.x = x;
  series.y = y;
  series.values = values;
  series_.push_back(std::move(series));
  colour_scale_ = scale;
}

void Chart::add_scatter(const std::vector<double>& x, const std::vector<double>& y, Colour colour,
                        const std::string& legend) {
  if (x.size() != y.size()) throw std::invalid_argument("scatter: x and y differ in length");
  series_.push_back({Kind::kScatter, x, y, {}, colour, legend, false});
}

void Chart::add_line(const std::vector<double>& x, const std::vector<double>& y, Colour colour,
                     const std::string& legend, bool dashed) {
  if (x.size() != y.size()) throw std::invalid_argument("line: x and y differ in length");
  series_.push_back({Kind::kLine, x, y, {}, colour, legend, dashed});
}

void Chart::add_horizontal_line(double y, Colour colour, const std::string& legend) {
  series_.push_back({Kind::kHorizontalLine, {}, {y}, {}, colour, legend, true});
}

void Chart::add_vertical_line(double x, Colour colour, const std::string& legend) {
  series_.push_back({Kind::kVerticalLine, {x}, {}, {}, colour, legend, true});
}

void Chart::add_histogram(const std::vector<double>& edges, const std::vector<double>& counts,
                          Colour colour, const std::string& legend) {
  if (edges.size() != counts.size() + 1) {
    throw std::invalid_argument("histogram: needs one more edge than counts");
  }
  series_.push_back({Kind::kHistogram, edges, counts, {}, colour, legend, false});
}

Chart::Layout Chart::layout() const {
  bool has_legend = false;
  bool include_zero_y = false;
  std::vector<double> xs, ys;
  for (const Series& s : series_) {
    has_legend |= !s.legend.empty();
    include_zero_y |= s.kind == Kind::kHistogram;
    if (s.kind != Kind::kHorizontalLine) xs.insert(xs.end(), s.x.begin(), s.x.end());
    if (s.kind != Kind::kVerticalLine) ys.insert(ys.end(), s.y.begin(), s.y.end());
  }
  const bool side_panel = has_legend || colour_scale_.has_value();
  Layout layout;
  layout.plot_left = kMarginLeft;
  layout.plot_right = width_ - kMarginRightPlain - (side_panel ? kSidePanelWidth : 0);
  layout.plot_top = kMarginTop;
  layout.plot_bottom = height_ - kMarginBottom;
  layout.sx = make_scale(x_axis_, xs, false);
  layout.sy = make_scale(y_axis_, ys, include_zero_y);
  layout.sx.pixel_lo = layout.plot_left;
  layout.sx.pixel_hi = layout.plot_right;
  layout.sy.pixel_lo = layout.plot_bottom;
  layout.sy.pixel_hi = layout.plot_top;
  return layout;
}

// Grid, ticks, tick labels and axis labels.
void Chart::render_axes(std::ostream& out, const Layout& layout) const {
  const auto& [plot_left, plot_right, plot_top, plot_bottom, sx, sy] = layout;
  // Grid, ticks and tick labels.
  double x_step = 0.0, y_step = 0.0;
  out << "<g class=\"axes\" stroke=\"#dddddd\" stroke-width=\"1\">\n";
  const std::vector<double> x_ticks = sx.ticks(&x_step);
  const std::vector<double> y_ticks = sy.ticks(&y_step);
  for (double t : x_ticks) {
    out << "<line x1=\"" << num(sx.to_pixel(t)) << "\" y1=\"" << plot_top << "\" x2=\""
        << num(sx.to_pixel(t)) << "\" y2=\"" << plot_bottom << "\"/>\n";
  }
  for (double t : y_ticks) {
    out << "<line x1=\"" << plot_left << "\" y1=\"" << num(sy.to_pixel(t)) << "\" x2=\""
        << plot_right << "\" y2=\"" << num(sy.to_pixel(t)) << "\"/>\n";
  }
  out << "</g>\n<rect x=\"" << plot_left << "\" y=\"" << plot_top << "\" width=\""
      << plot_right - plot_left << "\" height=\"" << plot_bottom - plot_top
      << "\" fill=\"none\" stroke=\"#333333\"/>\n";
  for (double t : x_ticks) {
    out << text_element(sx.to_pixel(t), plot_bottom + 16, tick_label(t, x_step), "middle");
  }
  for (double t : y_ticks) {
    out << text_element(plot_left - 6, sy.to_pixel(t) + 4, tick_label(t, y_step), "end");
  }
  out << text_element(0.5 * (plot_left + plot_right), height_ - 14, x_axis_.label, "middle",
                      " font-size=\"13\"");
  const double y_mid = 0.5 * (plot_top + plot_bottom);
  out << text_element(18, y_mid, y_axis_.label, "middle",
                      " font-size=\"13\" transform=\"rotate(-90 18 " + num(y_mid) + ")\"");
}

// The series in the order added, and a note on points not drawn.
void Chart::render_series(std::ostream& out, const Layout& layout) const {
  const auto& [plot_left, plot_right, plot_top, plot_bottom, sx, sy] = layout;
  int hidden_points = 0;
  std::string note;
  for (const Series& s : series_) {
    switch (s.kind) {
      case Kind::kHistogram:
        for (size_t i = 0; i + 1 < s.x.size(); ++i) {
          if (!sx.drawable(s.x[i]) || !sx.drawable(s.x[i + 1]) || !(s.y[i] > 0)) continue;
          const double x0 = sx.to_pixel(s.x[i]), x1 = sx.to_pixel(s.x[i + 1]);
          const double top = sy.to_pixel(s.y[i]), base = sy.to_pixel(sy.log ? sy.lo : 0.0);
          out << "<rect x=\"" << num(x0) << "\" y=\"" << num(top) << "\" width=\"" << num(x1 - x0)
              << "\" height=\"" << num(base - top) << "\" fill=\"" << s.colour.hex()
              << "\" stroke=\"#ffffff\" stroke-width=\"0.5\"/>\n";
        }
        break;
      case Kind::kLine: {
        std::string points;
        for (size_t i = 0; i < s.x.size(); ++i) {
          if (!sx.drawable(s.x[i]) || !sy.drawable(s.y[i])) continue;
          points += (points.empty() ? "" : " ") + num(sx.to_pixel(s.x[i])) + "," +
                    num(sy.to_pixel(s.y[i]));
        }
        out << "<polyline fill=\"none\" points=\"" << points << "\""
            << line_style(s.colour, 2.0, s.dashed) << "/>\n";
        break;
      }
      case Kind::kHorizontalLine:
        if (sy.drawable(s.y[0])) {
          out << "<line x1=\"" << plot_left << "\" y1=\"" << num(sy.to_pixel(s.y[0])) << "\" x2=\""
              << plot_right << "\" y2=\"" << num(sy.to_pixel(s.y[0])) << "\""
              << line_style(s.colour, 1.5, true) << "/>\n";
        }
        break;
      case Kind::kVerticalLine:
        if (sx.drawable(s.x[0])) {
          out << "<line x1=\"" << num(sx.to_pixel(s.x[0])) << "\" y1=\"" << plot_top << "\" x2=\""
              << num(sx.to_pixel(s.x[0])) << "\" y2=\"" << plot_bottom << "\""
              << line_style(s.colour, 1.5, true) << "/>\n";
        }
        break;
      case Kind::kScatter:
      case Kind::kValueScatter: {
        const size_t stride = s.x.size() / kMaxScatterPoints + 1;
        if (stride > 1) {
          note = "showing 1 in " + std::to_string(stride) + " of " + std::to_string(s.x.size()) +
                 " points";
        }
        out << "<g fill-opacity=\"0.8\">\n";
        for (size_t i = 0; i < s.x.size(); i += stride) {
          if (!sx.drawable(s.x[i]) || !sy.drawable(s.y[i])) {
            ++hidden_points;
            continue;
          }
          Colour colour = s.colour;
          if (s.kind == Kind::kValueScatter) {
            const double span = colour_scale_->max - colour_scale_->min;
            colour = viridis(span > 0 ? (s.values[i] - colour_scale_->min) / span : 0.5);
          }
          out << "<circle cx=\"" << num(sx.to_pixel(s.x[i])) << "\" cy=\""
              << num(sy.to_pixel(s.y[i])) << "\" r=\"3\" fill=\"" << colour.hex() << "\"/>\n";
        }
        out << "</g>\n";
        break;
      }
    }
  }
  if (hidden_points > 0) {
    note += (note.empty() ? "" : "; ") + std::to_string(hidden_points) +
            " points <= 0 not drawn on the log axis";
  }
  if (!note.empty()) {
    out << text_element(plot_right, plot_top - 6, note, "end", " font-size=\"10\"");
  }
}

// The legend, then the colour bar, right of the plot area.
void Chart::render_side_panel(std::ostream& out, const Layout& layout) const {
  const auto& [plot_left, plot_right, plot_top, plot_bottom, sx, sy] = layout;
  double side_y = plot_top + 6;
  const double side_x = plot_right + 16;
  for (const Series& s : series_) {
    if (s.legend.empty()) continue;
    if (s.kind == Kind::kScatter) {
      out << "<circle cx=\"" << num(side_x + 12) << "\" cy=\"" << num(side_y) << "\" r=\"4\" "
          << "fill=\"" << s.colour.hex() << "\"/>\n";
    } else if (s.kind == Kind::kHistogram) {
      out << "<rect x=\"" << num(side_x + 4) << "\" y=\"" << num(side_y - 6)
          << "\" width=\"16\" height=\"12\" fill=\"" << s.colour.hex() << "\"/>\n";
    } else {
      out << "<line x1=\"" << num(side_x) << "\" y1=\"" << num(side_y) << "\" x2=\""
          << num(side_x + 24) << "\" y2=\"" << num(side_y) << "\""
          << line_style(s.colour, 2.0, s.dashed || s.kind != Kind::kLine) << "/>\n";
    }
    // Wrapped to the panel: a long entry (a name with its n) is not cut off at the edge.
    const std::vector<std::string> lines =
        wrap_words(s.legend, chars_fitting(width_ - side_x - 32));
    for (const std::string& line : lines) {
      out << text_element(side_x + 30, side_y + 4, line, "start");
      side_y += 15;
    }
    side_y += 5;
  }
  if (colour_scale_) {
    constexpr int kSteps = 40;
    const double bar_top = side_y + 24;
    const double bar_height = std::max(60.0, plot_bottom - bar_top - 10);
    out << text_element(side_x, bar_top - 10, colour_scale_->label, "start");
    for (int i = 0; i < kSteps; ++i) {
      // Top of the bar is the maximum.
      const double t = 1.0 - (i + 0.5) / kSteps;
      out << "<rect x=\"" << num(side_x) << "\" y=\"" << num(bar_top + i * bar_height / kSteps)
          << "\" width=\"16\" height=\"" << num(bar_height / kSteps + 0.3) << "\" fill=\""
          << viridis(t).hex() << "\"/>\n";
    }
    Scale bar;
    bar.lo = colour_scale_->min;
    bar.hi =
        colour_scale_->max > colour_scale_->min ? colour_scale_->max : colour_scale_->min + 1.0;
    bar.pixel_lo = bar_top + bar_height;
    bar.pixel_hi = bar_top;
    // Values above the maximum take its colour: the top of the bar says so ("\u2265 3").
    double step = 0.0;
    const std::vector<double> ticks = bar.ticks(&step);
    const auto at_top = [&](double t) { return std::abs(t - bar.hi) <= 1e-9 * (1 + std::abs(t)); };
    if (std::none_of(ticks.begin(), ticks.end(), at_top)) {
      out << text_element(side_x + 22, bar_top + 4, "\u2265 " + batch::printf_general(bar.hi, 3),
                          "start");
    }
    for (double t : ticks) {
      if (!at_top(t) && bar.to_pixel(t) < bar_top + 14) continue;  // under the top label
      out << text_element(side_x + 22, bar.to_pixel(t) + 4,
                          (at_top(t) ? "\u2265 " : "") + tick_label(t, step), "start");
    }
  }
}

std::string Chart::render() const {
  const Layout frame = layout();
  std::ostringstream out;
  out << svg_open(width_, height_, title_);
  render_axes(out, frame);
  render_series(out, frame);
  render_side_panel(out, frame);
  out << "</svg>\n";
  return out.str();
}

std::string bar_chart(const std::string& title, const std::vector<Bar>& bars,
                      const AxisSpec& value_axis, int width) {
  constexpr int kRow = 24;
  constexpr int kLabelWidth = 170;
  // Room for the longest text at a bar's end ("100% (only 18% in the image)").
  int value_text_width = 60;
  for (const Bar& bar : bars) {
    value_text_width =
        std::max(value_text_width, static_cast<int>(std::ceil(bar.value_text.size() * 7.2)) + 12);
  }
  const int plot_left = kLabelWidth;
  const int plot_right = width - value_text_width;
  const int plot_top = kMarginTop;
  const int plot_bottom = plot_top + std::max<int>(1, bars.size()) * kRow;
  const int height = plot_bottom + kMarginBottom;
  std::vector<double> values;
  for (const Bar& bar : bars) values.push_back(bar.value);
  Scale sx = make_scale(value_axis, values, true);
  sx.pixel_lo = plot_left;
  sx.pixel_hi = plot_right;

  std::ostringstream out;
  out << svg_open(width, height, title);
  double step = 0.0;
  out << "<g stroke=\"#dddddd\">\n";
  const std::vector<double> ticks = sx.ticks(&step);
  for (double t : ticks) {
    out << "<line x1=\"" << num(sx.to_pixel(t)) << "\" y1=\"" << plot_top << "\" x2=\""
        << num(sx.to_pixel(t)) << "\" y2=\"" << plot_bottom << "\"/>\n";
  }
  out << "</g>\n";
  for (double t : ticks) {
    out << text_element(sx.to_pixel(t), plot_bottom + 16, tick_label(t, step), "middle");
  }
  out << text_element(0.5 * (plot_left + plot_right), height - 14, value_axis.label, "middle",
                      " font-size=\"13\"");
  const double base = sx.to_pixel(sx.log ? sx.lo : std::max(0.0, sx.lo));
  for (size_t i = 0; i < bars.size(); ++i) {
    const Bar& bar = bars[i];
    const double y = plot_top + i * kRow;
    const double end = sx.drawable(bar.value) ? sx.to_pixel(bar.value) : base;
    out << text_element(plot_left - 8, y + kRow / 2 + 4, bar.label, "end");
    out << "<rect x=\"" << num(std::min(base, end)) << "\" y=\"" << num(y + 4) << "\" width=\""
        << num(std::abs(end - base)) << "\" height=\"" << kRow - 8 << "\" fill=\""
        << bar.colour.hex() << "\"/>\n";
    out << text_element(std::max(base, end) + 6, y + kRow / 2 + 4, bar.value_text, "start",
                        " fill=\"" + bar.text_colour.hex() + "\" font-weight=\"bold\"");
  }
  out << "<line x1=\"" << plot_left << "\" y1=\"" << plot_top << "\" x2=\"" << plot_left
      << "\" y2=\"" << plot_bottom << "\" stroke=\"#333333\"/>\n";
  out << "<line x1=\"" << plot_left << "\" y1=\"" << plot_bottom << "\" x2=\"" << plot_right
      << "\" y2=\"" << plot_bottom << "\" stroke=\"#333333\"/>\n";
  out << "</svg>\n";
  return out.str();
}

}  // namespace clutterscope::report::svg
