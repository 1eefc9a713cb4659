#pragma once

// A small self-contained SVG plotting module for the report: charts with linear or log axes
// (ticks, tick labels, axis labels with units), scatter plots coloured by a value with a
// colour bar, lines with a legend, reference (threshold) lines, histograms, horizontal bar
// charts, and images with projected points. Output is deterministic text (fixed decimals), a
// bare <svg> element with its namespace, fit for inlining in HTML or saving as a file.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace cv {
class Mat;
}

namespace clutterscope::report::svg {

struct Colour {
  std::uint8_t r = 0, g = 0, b = 0;
  std::string hex() const;  // "#rrggbb"
};

// Perceptually ordered colour map (viridis anchors, linearly interpolated), t in [0, 1].
Colour viridis(double t);
// Distinct colours for categories (objects), cycling after 10.
Colour category_colour(int index);
// Red used for values below a visibility cutoff (paper Fig. 5).
Colour warning_red();

// Escapes &, <, >, " and ' for XML text and attributes.
std::string escape_xml(const std::string& text);

struct AxisSpec {
  std::string label;  // with its unit, e.g. "visibility V_i (%)"
  bool log_scale = false;
  std::optional<double> min;  // data range when empty
  std::optional<double> max;
};

struct ColourScale {
  std::string label;  // colour bar label with its unit
  double min = 0.0;
  double max = 1.0;
};

// An x-y chart. Add series, then render().
class Chart {
 public:
  Chart(std::string title, AxisSpec x_axis, AxisSpec y_axis, int width = 720, int height = 440);

  // Points coloured by `values` through viridis over `scale` (values clamped), with a colour
  // bar. Points that cannot be drawn on a log axis (<= 0) are counted in a note.
  void add_scatter(const std::vector<double>& x, const std::vector<double>& y,
                   const std::vector<double>& values, const ColourScale& scale);
  // Points of one colour, listed in the legend.
  void add_scatter(const std::vector<double>& x, const std::vector<double>& y, Colour colour,
                   const std::string& legend);
  void add_line(const std::vector<double>& x, const std::vector<double>& y, Colour colour,
                const std::string& legend, bool dashed = false);
  // Reference lines across the plot (e.g. the variance threshold), listed in the legend.
  void add_horizontal_line(double y, Colour colour, const std::string& legend);
  void add_vertical_line(double x, Colour colour, const std::string& legend);
  // Bars over [edges[i], edges[i+1]) of height counts[i] (edges.size() == counts.size() + 1).
  void add_histogram(const std::vector<double>& edges, const std::vector<double>& counts,
                     Colour colour, const std::string& legend);

  std::string render() const;

 private:
  // The steps of render(), over the plot area and scales of one render (svg_chart.cpp).
  struct Layout;
  Layout layout() const;
  void render_axes(std::ostream& out, const Layout& layout) const;
  void render_series(std::ostream& out, const Layout& layout) const;
  void render_side_panel(std::ostream& out, const Layout& layout) const;

  enum class Kind { kValueScatter, kScatter, kLine, kHorizontalLine, kVerticalLine, kHistogram };
  struct Series {
    Kind kind = Kind::kScatter;
    std::vector<double> x, y, values;  // histogram: x = edges, y = counts
    Colour colour;
    std::string legend;
    bool dashed = false;
  };
  std::string title_;
  AxisSpec x_axis_, y_axis_;
  int width_, height_;
  std::vector<Series> series_;
  std::optional<ColourScale> colour_scale_;
};

// One bar of a horizontal bar chart: a category label, its value, the bar colour and the
// text written at the bar's end (e.g. "86%", red below a cutoff).
struct Bar {
  std::string label;
  double value = 0.0;
  Colour colour;
  std::string value_text;
  Colour text_colour;
};

// Horizontal bars, one row per category, value axis along x.
std::string bar_chart(const std::string& title, const std::vector<Bar>& bars,
                      const AxisSpec& value_axis, int width = 720);

// A PNG image to draw points on, embedded in the SVG as a base64 data URI.
struct BackgroundImage {
  std::string png_bytes;
  int width = 0;
  int height = 0;

  // Reads a PNG file; throws datasets::DatasetError when unreadable or not a PNG.
  static BackgroundImage from_png_file(const std::filesystem::path& path);
  // Encodes an 8-bit image (1, 3 channels BGR, or 4 channels BGRA) as PNG.
  static BackgroundImage from_raster(const cv::Mat& image);
};

// 2-D points of one object in image pixels (u right, v down).
struct ProjectedObject {
  std::string label;
  Colour colour;
  std::vector<std::array<double, 2>> points;          // belief samples, drawn as dots
  std::optional<std::array<double, 2>> estimate;      // final estimate, drawn as a ringed cross
  bool estimate_confident = true;                     // false: a dashed ring and no cross
  std::optional<std::array<double, 2>> ground_truth;  // drawn as a hollow diamond
  // Short text beside the estimate (else the ground-truth) marker, e.g. a pick order "#1" or a
  // gt id: placed where it overlaps no other tag of the panel, so stacked objects whose
  // markers overlap stay told apart. Empty: none.
  std::string tag;
};

// Projects camera-frame points (metres, OpenCV pinhole) to image pixel coordinates with K:
// (u, v) = (fx x / z + cx, fy y / z + cy). Under the default pixel-centre convention (DESIGN
// §3), pixel (i, j) covers [i, i + 1) x [j, j + 1), exactly the SVG image's coordinates, so no
// shift is applied. Points with z <= 0 (behind the camera) are dropped.
std::vector<std::array<double, 2>> project_to_pixels(const Eigen::Matrix3d& K,
                                                     const std::vector<Eigen::Vector3d>& points);

// One panel: the image with every object's points (e.g. "initial beliefs", "iteration 15",
// "final estimates" as in the paper's Fig. 2 d-f and Fig. 3).
struct ImagePanel {
  std::string title;
  std::vector<ProjectedObject> objects;
};

// How image_panels arranges its panels.
struct PanelLayout {
  int panel_width = 360;  // pixels; the image is scaled to it
  int columns = 0;        // panels per row; 0: all in one row
  // true: each panel lists its own objects under it (panels that show different things, e.g.
  // simulate's estimates and picks); false: one legend of every label under all panels.
  bool legend_per_panel = false;
};

// Panels in rows over the same background, with a legend of object labels in their colours
// and, when a panel has estimates or ground truth, of the markers. Points outside the image
// are clipped. The background is embedded once (an <image> in <defs> that each panel <use>s,
// its id derived from the title and the image).
std::string image_panels(const std::string& title, const BackgroundImage& background,
                         const std::vector<ImagePanel>& panels, const PanelLayout& layout);
// All panels in one row, `panel_width` pixels each, one legend.
std::string image_panels(const std::string& title, const BackgroundImage& background,
                         const std::vector<ImagePanel>& panels, int panel_width = 360);

// Base64 (RFC 4648, with padding).
std::string base64(const std::string& bytes);

}  // namespace clutterscope::report::svg
