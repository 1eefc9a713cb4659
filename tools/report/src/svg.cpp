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

PanelLegend panel_legend(const std::vector<ImagePanel>& panels) {
  PanelLegend legend;
  for (const ImagePanel& panel : panels) {
    for (const ProjectedObject& object : panel.objects) {
      const bool listed =
          std::any_of(legend.labels.begin(), legend.labels.end(),
                      [&](const auto& entry) { return entry.first == object.label; });
      if (!listed) legend.labels.emplace_back(object.label, object.colour);
      legend.any_samples |= !object.points.empty();
      legend.any_confident |= object.estimate && object.estimate_confident;
      legend.any_uncertain |= object.estimate && !object.estimate_confident;
      legend.any_truth |= object.ground_truth.has_value();
    }
  }
  return legend;
}

// One panel's samples and markers over its copy of the background at (left, top), scaled by
// `scale`; points outside the image are clipped.
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
  const PanelLegend legend_entries = panel_legend(panels);
  const auto& [legend, any_samples, any_confident, any_uncertain, any_truth] = legend_entries;
  const bool marker_legend = any_confident || any_uncertain || any_truth;
  const int legend_rows =
      (static_cast<int>(legend.size()) + kLegendPerRow - 1) / kLegendPerRow + marker_legend;
  const int width = kGap + count * (panel_width + kGap);
  const int images_top = kMarginTop + kPanelTitle;
  const int height = images_top + panel_height + kGap + legend_rows * kLegendRow + kGap;
  // Distinct for the figures of one HTML page.
  const std::string id =
      "bg-" + batch::format_hex64(datasets::fnv1a64(title + background.png_bytes));

  std::ostringstream out;
  out << svg_open(width, height, title);
  out << "<defs><image id=\"" << id << "\" width=\"" << panel_width << "\" height=\""
      << panel_height << "\" preserveAspectRatio=\"none\" href=\"data:image/png;base64,"
      << base64(background.png_bytes) << "\"/></defs>\n";
  for (size_t p = 0; p < panels.size(); ++p) {
    const double left = kGap + p * (panel_width + kGap);
    out << text_element(left + panel_width / 2.0, images_top - 8, panels[p].title, "middle",
                        " font-size=\"13\"");
    out << "<use href=\"#" << id << "\" x=\"" << num(left) << "\" y=\"" << images_top << "\"/>\n";
    draw_objects(out, panels[p], background, left, images_top, scale);
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
