#include <charconv>
#include <clutterscope/visibility/scene_gt_info.hpp>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace clutterscope::visibility {

std::string python_float_repr(double value) {
  if (std::isnan(value)) return "NaN";  // what json.dumps writes; we never produce it
  if (std::isinf(value)) return value > 0 ? "Infinity" : "-Infinity";
  if (value == 0.0) return std::signbit(value) ? "-0.0" : "0.0";
  // Shortest round-trip digits, as "d.ddde[+-]XX".
  char buffer[64];
  const auto result =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::scientific);
  if (result.ec != std::errc()) throw std::runtime_error("python_float_repr: to_chars failed");
  const std::string scientific(buffer, result.ptr);
  const std::size_t e_pos = scientific.find('e');
  std::string mantissa = scientific.substr(0, e_pos);
  const int exponent = std::atoi(scientific.c_str() + e_pos + 1);
  std::string sign;
  if (mantissa[0] == '-') {
    sign = "-";
    mantissa.erase(0, 1);
  }
  std::string digits;
  for (char c : mantissa) {
    if (c != '.') digits += c;
  }
  if (exponent < -4 || exponent >= 16) {
    std::string out = sign + digits.substr(0, 1);
    if (digits.size() > 1) out += "." + digits.substr(1);
    const int magnitude = std::abs(exponent);
    out += exponent < 0 ? "e-" : "e+";
    if (magnitude < 10) out += "0";
    return out + std::to_string(magnitude);
  }
  // Fixed notation: the decimal point sits after digit number exponent + 1.
  const int point = exponent + 1;
  std::string integer_part, fraction_part;
  if (point <= 0) {
    integer_part = "0";
    fraction_part = std::string(static_cast<std::size_t>(-point), '0') + digits;
  } else if (static_cast<std::size_t>(point) >= digits.size()) {
    integer_part = digits + std::string(static_cast<std::size_t>(point) - digits.size(), '0');
    fraction_part = "0";
  } else {
    integer_part = digits.substr(0, static_cast<std::size_t>(point));
    fraction_part = digits.substr(static_cast<std::size_t>(point));
  }
  return sign + integer_part + "." + fraction_part;
}

namespace {
std::string box_json(const BopBox& box) {
  return "[" + std::to_string(box[0]) + ", " + std::to_string(box[1]) + ", " +
         std::to_string(box[2]) + ", " + std::to_string(box[3]) + "]";
}
}  // namespace

std::string gt_info_json(const BopGtInfo& info) {
  return "{\"bbox_obj\": " + box_json(info.bbox_obj) +
         ", \"bbox_visib\": " + box_json(info.bbox_visib) +
         ", \"px_count_all\": " + std::to_string(info.px_count_all) +
         ", \"px_count_valid\": " + std::to_string(info.px_count_valid) +
         ", \"px_count_visib\": " + std::to_string(info.px_count_visib) +
         ", \"visib_fract\": " + python_float_repr(info.visib_fract) + "}";
}

std::string scene_gt_info_json(const std::map<int, std::vector<BopGtInfo>>& images) {
  std::string out = "{\n";
  std::size_t written = 0;
  for (const auto& [im_id, instances] : images) {
    out += "  \"" + std::to_string(im_id) + "\": [";
    for (std::size_t i = 0; i < instances.size(); ++i) {
      if (i > 0) out += ", ";
      out += gt_info_json(instances[i]);
    }
    out += "]";
    if (++written != images.size()) out += ",";
    out += "\n";
  }
  return out + "}";
}

}  // namespace clutterscope::visibility
