#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/report/svg.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>

namespace clutterscope::report::svg {

namespace {

// Above this many points a scatter draws an evenly strided subset (noted on the chart), so a
// report over a large dataset stays a reasonably sized HTML file.
constexpr size_t kMaxScatterPoints = 20000;

constexpr int kMarginLeft = 78;
constexpr int kMarginTop = 40;
constexpr int kMarginBottom = 56;
constexpr int kMarginRightPlain = 24;
constexpr int kSidePanelWidth = 190;  // legend and colour bar, right of the plot area
constexpr const char* kFont = "font-family=\"DejaVu Sans, Arial, sans-serif\"";

std::string num(double value) {
  const std::string text = batch::printf_fixed(value, 2);
  return text == "-0.00" ? "0.00" : text;
}

std::string svg_open(int width, int height, const std::string& title) {
  std::ostringstream out;
  out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" viewBox=\"0 0 " << width << ' ' << height << "\" role=\"img\" " << kFont
      << " font-size=\"12\">\n<title>" << escape_xml(title) << "</title>\n"
      << "<rect width=\"" << width << "\" height=\"" << height << "\" fill=\"#ffffff\"/>\n"
      << "<text x=\"" << width / 2 << "\" y=\"24\" text-anchor=\"middle\" font-size=\"15\" "
      << "font-weight=\"bold\">" << escape_xml(title) << "</text>\n";
  return out.str();
}

std::string text_element(double x, double y, const std::string& text, const char* anchor,
                         const std::string& extra = "") {
  std::ostringstream out;
  out << "<text x=\"" << num(x) << "\" y=\"" << num(y) << "\" text-anchor=\"" << anchor << "\""
      << extra << ">" << escape_xml(text) << "</text>\n";
  return out.str();
}

// Tick label for a value: as few decimals as the tick step needs.
std::string tick_label(double value, double step) {
  std::string text;
  if (step <= 0.0) {
    text = batch::printf_general(value);
  } else {
    const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
    text = batch::printf_fixed(value, decimals);
  }
  if (text.find_first_not_of("-0.") == std::string::npos) return "0";
  return text;
}

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
Scale make_scale(const AxisSpec& axis, std::vector<double> values, bool include_zero) {
  Scale scale;
  scale.log = axis.log_scale;
  values.erase(
      std::remove_if(values.begin(), values.end(), [&](double v) { return !scale.drawable(v); }),
      values.end());
  if (include_zero && !scale.log) values.push_back(0.0);
  double lo =
      values.empty() ? (scale.log ? 0.1 : 0.0) : *std::min_element(values.begin(), values.end());
  double hi =
      values.empty() ? (scale.log ? 10.0 : 1.0) : *std::max_element(values.begin(), values.end());
  if (scale.log) {
    lo = std::pow(10.0, std::floor(std::log10(lo) + 1e-9));
    hi = std::pow(10.0, std::ceil(std::log10(hi) - 1e-9));
    if (hi <= lo) hi = lo * 10.0;
  } else {
    if (hi <= lo) {
      const double pad = lo == 0.0 ? 1.0 : 0.5 * std::abs(lo);
      lo -= pad;
      hi += pad;
    } else {
      const double pad = 0.04 * (hi - lo);
      if (!(include_zero && lo == 0.0)) lo -= pad;
      hi += pad;
    }
  }
  if (axis.min && scale.drawable(*axis.min)) lo = *axis.min;
  if (axis.max && scale.drawable(*axis.max)) hi = *axis.max;
  if (hi <= lo) hi = scale.log ? lo * 10.0 : lo + 1.0;
  scale.lo = lo;
  scale.hi = hi;
  return scale;
}

std::string line_style(Colour colour, double width, bool dashed) {
  std::string style = " stroke=\"" + colour.hex() + "\" stroke-width=\"" + num(width) + "\"";
  if (dashed) style += " stroke-dasharray=\"6 4\"";
  return style;
}

}  // namespace

std::string Colour::hex() const {
  char buffer[8];
  std::snprintf(buffer, sizeof(buffer), "#%02x%02x%02x", r, g, b);
  return buffer;
}

Colour viridis(double t) {
  static const Colour anchors[] = {{68, 1, 84},    {72, 40, 120},  {62, 74, 137},  {49, 104, 142},
                                   {38, 130, 142}, {31, 158, 137}, {53, 183, 121}, {109, 205, 89},
                                   {180, 222, 44}, {253, 231, 37}};
  constexpr int kLast = sizeof(anchors) / sizeof(anchors[0]) - 1;
  const double position = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * kLast;
  const int i = std::min(static_cast<int>(position), kLast - 1);
  const double f = position - i;
  const auto mix = [&](std::uint8_t a, std::uint8_t b) {
    return static_cast<std::uint8_t>(std::lround(a + f * (b - a)));
  };
  return {mix(anchors[i].r, anchors[i + 1].r), mix(anchors[i].g, anchors[i + 1].g),
          mix(anchors[i].b, anchors[i + 1].b)};
}

Colour category_colour(int index) {
  static const Colour palette[] = {
      {31, 119, 180}, {255, 127, 14},  {44, 160, 44},   {214, 39, 40},  {148, 103, 189},
      {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};
  return palette[((index % 10) + 10) % 10];
}

Colour warning_red() { return {204, 0, 0}; }

std::string escape_xml(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        // Control characters other than tab/newline are not allowed in XML 1.0.
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n') {
          out += ' ';
        } else {
          out += c;
        }
    }
  }
  return out;
}

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

std::string Chart::render() const {
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
  const int plot_left = kMarginLeft;
  const int plot_right = width_ - kMarginRightPlain - (side_panel ? kSidePanelWidth : 0);
  const int plot_top = kMarginTop;
  const int plot_bottom = height_ - kMarginBottom;
  Scale sx = make_scale(x_axis_, xs, false);
  Scale sy = make_scale(y_axis_, ys, include_zero_y);
  sx.pixel_lo = plot_left;
  sx.pixel_hi = plot_right;
  sy.pixel_lo = plot_bottom;
  sy.pixel_hi = plot_top;

  std::ostringstream out;
  out << svg_open(width_, height_, title_);
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

  // Series.
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

  // Legend, then colour bar, right of the plot area.
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
    out << text_element(side_x + 30, side_y + 4, s.legend, "start");
    side_y += 20;
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
    double step = 0.0;
    for (double t : bar.ticks(&step)) {
      out << text_element(side_x + 22, bar.to_pixel(t) + 4, tick_label(t, step), "start");
    }
  }
  out << "</svg>\n";
  return out.str();
}

std::string bar_chart(const std::string& title, const std::vector<Bar>& bars,
                      const AxisSpec& value_axis, int width) {
  constexpr int kRow = 24;
  constexpr int kLabelWidth = 170;
  constexpr int kValueTextWidth = 60;
  const int plot_left = kLabelWidth;
  const int plot_right = width - kValueTextWidth;
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

BackgroundImage BackgroundImage::from_png_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw datasets::DatasetError(path, "cannot open image");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  BackgroundImage image;
  image.png_bytes = bytes.str();
  const std::string& b = image.png_bytes;
  static const char kSignature[] = "\x89PNG\r\n\x1a\n";
  // Signature, then the IHDR chunk: length, "IHDR", width and height as big-endian uint32.
  if (b.size() < 24 || b.compare(0, 8, kSignature, 8) != 0 || b.compare(12, 4, "IHDR") != 0) {
    throw datasets::DatasetError(path, "not a PNG image");
  }
  const auto big_endian = [&](size_t offset) {
    std::uint32_t value = 0;
    for (size_t i = 0; i < 4; ++i) value = (value << 8) | static_cast<unsigned char>(b[offset + i]);
    return value;
  };
  const std::uint32_t width = big_endian(16), height = big_endian(20);
  if (width == 0 || height == 0 || width > 1u << 16 || height > 1u << 16) {
    throw datasets::DatasetError(path, "PNG header has an invalid size");
  }
  image.width = static_cast<int>(width);
  image.height = static_cast<int>(height);
  return image;
}

BackgroundImage BackgroundImage::from_raster(const cv::Mat& raster) {
  if (raster.empty() || raster.depth() != CV_8U ||
      (raster.channels() != 1 && raster.channels() != 3 && raster.channels() != 4)) {
    throw std::invalid_argument("background raster must be 8-bit with 1, 3 or 4 channels");
  }
  std::vector<unsigned char> buffer;
  if (!cv::imencode(".png", raster, buffer)) {
    throw std::runtime_error("PNG encoding of the background image failed");
  }
  BackgroundImage image;
  image.png_bytes.assign(buffer.begin(), buffer.end());
  image.width = raster.cols;
  image.height = raster.rows;
  return image;
}

std::string base64(const std::string& bytes) {
  static const char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t chunk = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) chunk |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) chunk |= static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[(chunk >> 18) & 63];
    out += kAlphabet[(chunk >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(chunk >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[chunk & 63] : '=';
  }
  return out;
}

std::vector<std::array<double, 2>> project_to_pixels(const Eigen::Matrix3d& K,
                                                     const std::vector<Eigen::Vector3d>& points) {
  std::vector<std::array<double, 2>> pixels;
  pixels.reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    if (!(p.z() > 0.0)) continue;
    pixels.push_back({K(0, 0) * p.x() / p.z() + K(0, 2), K(1, 1) * p.y() / p.z() + K(1, 2)});
  }
  return pixels;
}

namespace {

// Estimate and ground-truth markers centred at (cx, cy), in `colour` over a white halo.
std::string estimate_marker(double cx, double cy, Colour colour, bool confident) {
  std::ostringstream out;
  if (confident) {
    out << "<g stroke=\"" << colour.hex() << "\" stroke-width=\"2\" fill=\"none\">"
        << "<circle cx=\"" << num(cx) << "\" cy=\"" << num(cy) << "\" r=\"7\" "
        << "stroke=\"#ffffff\" stroke-width=\"4\"/><circle cx=\"" << num(cx) << "\" cy=\""
        << num(cy) << "\" r=\"7\"/><line x1=\"" << num(cx - 10) << "\" y1=\"" << num(cy)
        << "\" x2=\"" << num(cx + 10) << "\" y2=\"" << num(cy) << "\"/><line x1=\"" << num(cx)
        << "\" y1=\"" << num(cy - 10) << "\" x2=\"" << num(cx) << "\" y2=\"" << num(cy + 10)
        << "\"/></g>\n";
  } else {
    out << "<g stroke=\"" << colour.hex() << "\" stroke-width=\"2\" fill=\"none\">"
        << "<circle cx=\"" << num(cx) << "\" cy=\"" << num(cy) << "\" r=\"9\" "
        << "stroke=\"#ffffff\" stroke-width=\"4\"/><circle cx=\"" << num(cx) << "\" cy=\""
        << num(cy) << "\" r=\"9\" stroke-dasharray=\"3 3\"/><circle cx=\"" << num(cx) << "\" cy=\""
        << num(cy) << "\" r=\"2\" fill=\"" << colour.hex() << "\"/></g>\n";
  }
  return out.str();
}

std::string ground_truth_marker(double cx, double cy, Colour colour) {
  std::ostringstream out;
  const std::string points = num(cx) + "," + num(cy - 6) + " " + num(cx + 6) + "," + num(cy) + " " +
                             num(cx) + "," + num(cy + 6) + " " + num(cx - 6) + "," + num(cy);
  out << "<g fill=\"none\"><polygon points=\"" << points
      << "\" stroke=\"#ffffff\" stroke-width=\"4\"/><polygon points=\"" << points << "\" stroke=\""
      << colour.hex() << "\" stroke-width=\"2\"/></g>\n";
  return out.str();
}

// FNV-1a, for ids that differ between figures of one HTML page.
std::uint64_t fnv1a(const std::string& bytes) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (unsigned char c : bytes) hash = (hash ^ c) * 0x100000001b3ULL;
  return hash;
}

}  // namespace

std::string image_panels(const std::string& title, const BackgroundImage& background,
                         const std::vector<ImagePanel>& panels, int panel_width) {
  if (background.width <= 0 || background.height <= 0) {
    throw std::invalid_argument("image panels need a background image with a size");
  }
  constexpr int kGap = 12;
  constexpr int kPanelTitle = 22;
  constexpr int kLegendRow = 20;
  constexpr int kLegendPerRow = 4;
  const double scale = static_cast<double>(panel_width) / background.width;
  const int panel_height = static_cast<int>(std::lround(background.height * scale));
  const int count = std::max<int>(1, panels.size());
  std::vector<std::pair<std::string, Colour>> legend;
  bool any_samples = false, any_confident = false, any_uncertain = false, any_truth = false;
  for (const ImagePanel& panel : panels) {
    for (const ProjectedObject& object : panel.objects) {
      const bool listed = std::any_of(legend.begin(), legend.end(), [&](const auto& entry) {
        return entry.first == object.label;
      });
      if (!listed) legend.emplace_back(object.label, object.colour);
      any_samples |= !object.points.empty();
      any_confident |= object.estimate && object.estimate_confident;
      any_uncertain |= object.estimate && !object.estimate_confident;
      any_truth |= object.ground_truth.has_value();
    }
  }
  const bool marker_legend = any_confident || any_uncertain || any_truth;
  const int legend_rows =
      (static_cast<int>(legend.size()) + kLegendPerRow - 1) / kLegendPerRow + marker_legend;
  const int width = kGap + count * (panel_width + kGap);
  const int images_top = kMarginTop + kPanelTitle;
  const int height = images_top + panel_height + kGap + legend_rows * kLegendRow + kGap;
  char id[32];
  std::snprintf(id, sizeof(id), "bg-%016llx",
                static_cast<unsigned long long>(fnv1a(title + background.png_bytes)));

  std::ostringstream out;
  out << svg_open(width, height, title);
  out << "<defs><image id=\"" << id << "\" width=\"" << panel_width << "\" height=\""
      << panel_height << "\" preserveAspectRatio=\"none\" href=\"data:image/png;base64,"
      << base64(background.png_bytes) << "\"/></defs>\n";
  const auto inside = [&](const std::array<double, 2>& point) {
    return std::isfinite(point[0]) && std::isfinite(point[1]) && point[0] >= 0 && point[1] >= 0 &&
           point[0] <= background.width && point[1] <= background.height;
  };
  for (size_t p = 0; p < panels.size(); ++p) {
    const double left = kGap + p * (panel_width + kGap);
    out << text_element(left + panel_width / 2.0, images_top - 8, panels[p].title, "middle",
                        " font-size=\"13\"");
    out << "<use href=\"#" << id << "\" x=\"" << num(left) << "\" y=\"" << images_top << "\"/>\n";
    for (const ProjectedObject& object : panels[p].objects) {
      if (!object.points.empty()) {
        out << "<g fill=\"" << object.colour.hex() << "\" fill-opacity=\"0.75\">\n";
        for (const auto& point : object.points) {
          if (!inside(point)) continue;
          out << "<circle cx=\"" << num(left + point[0] * scale) << "\" cy=\""
              << num(images_top + point[1] * scale) << "\" r=\"1.8\"/>\n";
        }
        out << "</g>\n";
      }
      if (object.ground_truth && inside(*object.ground_truth)) {
        out << ground_truth_marker(left + (*object.ground_truth)[0] * scale,
                                   images_top + (*object.ground_truth)[1] * scale, object.colour);
      }
      if (object.estimate && inside(*object.estimate)) {
        out << estimate_marker(left + (*object.estimate)[0] * scale,
                               images_top + (*object.estimate)[1] * scale, object.colour,
                               object.estimate_confident);
      }
    }
  }
  const double legend_top = images_top + panel_height + kGap + kLegendRow / 2.0;
  const double legend_column = static_cast<double>(width - 2 * kGap) / kLegendPerRow;
  for (size_t i = 0; i < legend.size(); ++i) {
    const double x = kGap + (i % kLegendPerRow) * legend_column;
    const double y = legend_top + (i / kLegendPerRow) * kLegendRow;
    out << "<circle cx=\"" << num(x + 6) << "\" cy=\"" << num(y) << "\" r=\"5\" fill=\""
        << legend[i].second.hex() << "\"/>\n";
    out << text_element(x + 16, y + 4, legend[i].first, "start");
  }
  if (marker_legend) {
    const Colour grey{90, 90, 90};
    double x = kGap;
    const double y = legend_top + (legend_rows - 1) * kLegendRow;
    const auto entry = [&](const std::string& marker, const std::string& text) {
      out << marker << text_element(x + 24, y + 4, text, "start");
      x += legend_column;
    };
    if (any_samples) {
      entry("<circle cx=\"" + num(x + 10) + "\" cy=\"" + num(y) + "\" r=\"2.5\" fill=\"" +
                grey.hex() + "\"/>\n",
            "belief sample");
    }
    if (any_confident) entry(estimate_marker(x + 10, y, grey, true), "confident estimate");
    if (any_uncertain) entry(estimate_marker(x + 10, y, grey, false), "not confident estimate");
    if (any_truth) entry(ground_truth_marker(x + 10, y, grey), "ground-truth centre");
  }
  out << "</svg>\n";
  return out.str();
}

}  // namespace clutterscope::report::svg
