#include "svg_elements.hpp"

#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <cmath>
#include <sstream>

namespace clutterscope::report::svg::detail {

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
                         const std::string& extra) {
  std::ostringstream out;
  out << "<text x=\"" << num(x) << "\" y=\"" << num(y) << "\" text-anchor=\"" << anchor << "\""
      << extra << ">" << escape_xml(text) << "</text>\n";
  return out.str();
}

std::vector<std::string> wrap_words(const std::string& text, std::size_t max_chars) {
  std::vector<std::string> lines;
  std::string line;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find(' ', start);
    if (end == std::string::npos) end = text.size();
    const std::string word = text.substr(start, end - start);
    if (!line.empty() && line.size() + 1 + word.size() > max_chars) {
      lines.push_back(line);
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
    start = end + 1;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

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

}  // namespace clutterscope::report::svg::detail
