#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/random_streams.hpp>
#include <clutterscope/report/svg.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>

#include "svg_elements.hpp"

namespace clutterscope::report::svg {

using detail::chars_fitting;
using detail::kMarginTop;
using detail::num;
using detail::svg_open;
using detail::text_element;

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

// The legend of image panels: each object label once (first colour seen) and which markers
// occur.
struct PanelLegend {
  std::vector<std::pair<std::string, Colour>> labels;
  bool any_samples = false, any_confident = false, any_uncertain = false, any_truth = false;
};

void add_to_legend(const ImagePanel& panel, PanelLegend* legend) {
  for (const ProjectedObject& object : panel.objects) {
    const bool listed = std::any_of(legend->labels.begin(), legend->labels.end(),
                                    [&](const auto& entry) { return entry.first == object.label; });
    if (!listed) legend->labels.emplace_back(object.label, object.colour);
    legend->any_samples |= !object.points.empty();
    legend->any_confident |= object.estimate && object.estimate_confident;
    legend->any_uncertain |= object.estimate && !object.estimate_confident;
    legend->any_truth |= object.ground_truth.has_value();
  }
}

// An axis-aligned box of a placed tag, in SVG pixels.
struct Box {
  double left, top, right, bottom;
  bool overlaps(const Box& other) const {
    return left < other.right && other.left < right && top < other.bottom && other.top < bottom;
  }
};

// One panel's samples, markers and tags over its copy of the background at (left, top),
// scaled by `scale`; points outside the image are clipped.
void draw_objects(std::ostream& out, const ImagePanel& panel, const BackgroundImage& background,
                  double left, double top, double scale) {
  const auto inside = [&](const std::array<double, 2>& point) {
    return std::isfinite(point[0]) && std::isfinite(point[1]) && point[0] >= 0 && point[1] >= 0 &&
           point[0] <= background.width && point[1] <= background.height;
  };
  for (const ProjectedObject& object : panel.objects) {
    if (!object.points.empty()) {
      out << "<g fill=\"" << object.colour.hex() << "\" fill-opacity=\"0.75\">\n";
      for (const auto& point : object.points) {
        if (!inside(point)) continue;
        out << "<circle cx=\"" << num(left + point[0] * scale) << "\" cy=\""
            << num(top + point[1] * scale) << "\" r=\"1.8\"/>\n";
      }
      out << "</g>\n";
    }
    if (object.ground_truth && inside(*object.ground_truth)) {
      out << ground_truth_marker(left + (*object.ground_truth)[0] * scale,
                                 top + (*object.ground_truth)[1] * scale, object.colour);
    }
    if (object.estimate && inside(*object.estimate)) {
      out << estimate_marker(left + (*object.estimate)[0] * scale,
                             top + (*object.estimate)[1] * scale, object.colour,
                             object.estimate_confident);
    }
  }
  // Tags last, over every marker, each at the first spot around its marker that no earlier
  // tag of the panel covers (stacked objects project close together).
  std::vector<Box> placed;
  for (const ProjectedObject& object : panel.objects) {
    if (object.tag.empty()) continue;
    const auto& at =
        object.estimate && inside(*object.estimate) ? object.estimate : object.ground_truth;
    if (!at || !inside(*at)) continue;
    const double x = left + (*at)[0] * scale, y = top + (*at)[1] * scale;
    const double w = 7.0 * static_cast<double>(object.tag.size()) + 4, h = 14;
    // Right, left, above, below, then the diagonals, then further out to the right.
    const std::array<std::array<double, 2>, 9> offsets = {{{12, -7},
                                                           {-12 - w, -7},
                                                           {-w / 2, -12 - h},
                                                           {-w / 2, 12},
                                                           {10, -10 - h},
                                                           {-10 - w, -10 - h},
                                                           {10, 10},
                                                           {-10 - w, 10},
                                                           {26, -7}}};
    Box box{};
    for (const auto& offset : offsets) {
      box = {x + offset[0], y + offset[1], x + offset[0] + w, y + offset[1] + h};
      if (std::none_of(placed.begin(), placed.end(),
                       [&](const Box& other) { return box.overlaps(other); })) {
        break;
      }
    }
    placed.push_back(box);
    out << "<text x=\"" << num(box.left + 2) << "\" y=\"" << num(box.bottom - 3)
        << "\" font-size=\"11\" font-weight=\"bold\" fill=\"" << object.colour.hex()
        << "\" stroke=\"#ffffff\" stroke-width=\"3\" paint-order=\"stroke\">"
        << escape_xml(object.tag) << "</text>\n";
  }
}

constexpr int kLegendRow = 20;
constexpr int kLegendColumnWidth = 190;

int marker_entries(const PanelLegend& legend) {
  return legend.any_samples + legend.any_confident + legend.any_uncertain + legend.any_truth;
}

// Rows of a legend in `columns` columns: the labels, then the markers that occur.
int legend_rows(const PanelLegend& legend, int columns) {
  const int labels = static_cast<int>(legend.labels.size());
  return (labels + columns - 1) / columns + (marker_entries(legend) + columns - 1) / columns;
}

// A legend from (left, top) over `width` pixels in `columns` columns: the labels (cut to the
// column with "...", the whole label as the tooltip), then the markers that occur.
void draw_legend(std::ostream& out, const PanelLegend& legend, double left, double top,
                 double width, int columns) {
  const double column = width / columns;
  const std::size_t fitting = chars_fitting(column - 20);
  int slot = 0;  // entries drawn, row-major
  const auto position = [&]() {
    return std::make_pair(left + (slot % columns) * column, top + (slot / columns) * kLegendRow);
  };
  for (const auto& [label, colour] : legend.labels) {
    const auto [x, y] = position();
    out << "<circle cx=\"" << num(x + 6) << "\" cy=\"" << num(y) << "\" r=\"5\" fill=\""
        << colour.hex() << "\"/>\n";
    const std::string text =
        label.size() > fitting ? label.substr(0, fitting > 3 ? fitting - 3 : 0) + "..." : label;
    out << "<text x=\"" << num(x + 16) << "\" y=\"" << num(y + 4)
        << "\" text-anchor=\"start\"><title>" << escape_xml(label) << "</title>" << escape_xml(text)
        << "</text>\n";
    ++slot;
  }
  slot = (slot + columns - 1) / columns * columns;  // the markers start a row
  const Colour grey{90, 90, 90};
  const auto entry = [&](const std::string& kind, const std::string& text) {
    const auto [x, y] = position();
    const double cx = x + 10;
    if (kind == "sample") {
      out << "<circle cx=\"" << num(cx) << "\" cy=\"" << num(y) << "\" r=\"2.5\" fill=\""
          << grey.hex() << "\"/>\n";
    } else if (kind == "truth") {
      out << ground_truth_marker(cx, y, grey);
    } else {
      out << estimate_marker(cx, y, grey, kind == "confident");
    }
    out << text_element(x + 24, y + 4, text, "start");
    ++slot;
  };
  if (legend.any_samples) entry("sample", "belief sample");
  if (legend.any_confident) entry("confident", "confident estimate");
  if (legend.any_uncertain) entry("uncertain", "not confident estimate");
  if (legend.any_truth) entry("truth", "ground-truth centre");
}

}  // namespace

std::string image_panels(const std::string& title, const BackgroundImage& background,
                         const std::vector<ImagePanel>& panels, int panel_width) {
  return image_panels(title, background, panels, PanelLayout{panel_width, 0, false});
}

std::string image_panels(const std::string& title, const BackgroundImage& background,
                         const std::vector<ImagePanel>& panels, const PanelLayout& layout) {
  if (background.width <= 0 || background.height <= 0) {
    throw std::invalid_argument("image panels need a background image with a size");
  }
  constexpr int kGap = 12;
  constexpr int kPanelTitle = 22;
  const int panel_width = layout.panel_width;
  const double scale = static_cast<double>(panel_width) / background.width;
  const int panel_height = static_cast<int>(std::lround(background.height * scale));
  const int count = std::max<int>(1, panels.size());
  const int columns = layout.columns > 0 ? std::min(layout.columns, count) : count;
  const int rows = (count + columns - 1) / columns;
  const int width = kGap + columns * (panel_width + kGap);

  // The legends: one under every panel, or one for all under the last row.
  std::vector<PanelLegend> legends(layout.legend_per_panel ? panels.size() : 1);
  for (size_t p = 0; p < panels.size(); ++p) {
    add_to_legend(panels[p], &legends[layout.legend_per_panel ? p : 0]);
  }
  const int legend_width = layout.legend_per_panel ? panel_width : width - 2 * kGap;
  const int legend_columns = std::max(1, legend_width / kLegendColumnWidth);
  int legend_height = 0;  // of the tallest legend
  for (const PanelLegend& legend : legends) {
    legend_height = std::max(legend_height, legend_rows(legend, legend_columns) * kLegendRow);
  }
  // A row of panels: title, image, and with legend_per_panel each panel's legend.
  const int row_height =
      kPanelTitle + panel_height + kGap + (layout.legend_per_panel ? legend_height + kGap : 0);
  const int height =
      kMarginTop + rows * row_height + (layout.legend_per_panel ? 0 : legend_height + kGap);
  // Distinct for the figures of one HTML page.
  const std::string id =
      "bg-" + batch::format_hex64(datasets::fnv1a64(title + background.png_bytes));

  std::ostringstream out;
  out << svg_open(width, height, title);
  out << "<defs><image id=\"" << id << "\" width=\"" << panel_width << "\" height=\""
      << panel_height << "\" preserveAspectRatio=\"none\" href=\"data:image/png;base64,"
      << base64(background.png_bytes) << "\"/></defs>\n";
  for (size_t p = 0; p < panels.size(); ++p) {
    const double left = kGap + static_cast<double>(p % columns) * (panel_width + kGap);
    const int images_top = kMarginTop + static_cast<int>(p / columns) * row_height + kPanelTitle;
    out << text_element(left + panel_width / 2.0, images_top - 8, panels[p].title, "middle",
                        " font-size=\"13\"");
    out << "<use href=\"#" << id << "\" x=\"" << num(left) << "\" y=\"" << images_top << "\"/>\n";
    draw_objects(out, panels[p], background, left, images_top, scale);
    if (layout.legend_per_panel) {
      draw_legend(out, legends[p], left, images_top + panel_height + kGap + kLegendRow / 2.0,
                  panel_width, legend_columns);
    }
  }
  if (!layout.legend_per_panel) {
    draw_legend(out, legends.front(), kGap, kMarginTop + rows * row_height + kLegendRow / 2.0,
                width - 2 * kGap, legend_columns);
  }
  out << "</svg>\n";
  return out.str();
}

}  // namespace clutterscope::report::svg
