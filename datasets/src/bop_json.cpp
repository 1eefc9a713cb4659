#include "bop_json.hpp"

#include <Eigen/LU>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>
#include <tuple>
#include <utility>

namespace clutterscope::datasets {

double rotation_orthonormality_error(const Eigen::Matrix3d& rotation) {
  return (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
}

}  // namespace clutterscope::datasets

namespace clutterscope::datasets::detail {

namespace fs = std::filesystem;

namespace {

// Where inside `text` a parse error at `byte` happened: the last top-level key and the last
// key at any depth before it, found by a scan that skips over string contents.
struct ParsePlace {
  std::string top_key;
  std::string field;
};

ParsePlace place_of(const std::string& text, size_t byte) {
  ParsePlace place;
  int depth = 0;
  bool in_string = false;
  bool escaped = false;
  std::string current;
  std::string last_string;
  bool string_just_closed = false;
  const size_t end = std::min(byte, text.size());
  for (size_t i = 0; i < end; ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped) {
        escaped = false;
        current += c;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
        last_string = current;
        string_just_closed = true;
      } else {
        current += c;
      }
      continue;
    }
    if (std::isspace(static_cast<unsigned char>(c))) continue;
    if (c == ':' && string_just_closed) {
      place.field = last_string;
      if (depth == 1) place.top_key = last_string;
    }
    string_just_closed = false;
    if (c == '"') {
      in_string = true;
      current.clear();
    } else if (c == '{' || c == '[') {
      ++depth;
    } else if (c == '}' || c == ']') {
      --depth;
    }
  }
  return place;
}

}  // namespace

Json read_json_file(const fs::path& path, const std::string& where, const char* key_name) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) {
    throw DatasetError(path, where + "file is missing");
  }
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw DatasetError(path, where + "cannot open file for reading");
  std::stringstream buffer;
  buffer << stream.rdbuf();
  const std::string text = buffer.str();
  size_t error_byte = 0;
  std::string parser_message;
  try {
    return Json::parse(text);
  } catch (const Json::parse_error& parse_error) {
    error_byte = parse_error.byte;
    parser_message = parse_error.what();
  } catch (const Json::exception& other) {
    // e.g. out_of_range.406 "number overflow parsing '1e999'": locate the quoted token.
    parser_message = other.what();
    const size_t open = parser_message.find('\'');
    const size_t close = parser_message.rfind('\'');
    if (open != std::string::npos && close > open + 1) {
      const size_t at = text.find(parser_message.substr(open + 1, close - open - 1));
      if (at != std::string::npos) error_byte = at + 1;
    }
  }
  const ParsePlace place = place_of(text, error_byte);
  std::string message = where + "malformed JSON";
  if (!place.top_key.empty()) message += std::string(" in ") + key_name + " " + place.top_key;
  if (!place.field.empty() && place.field != place.top_key) message += ", field " + place.field;
  const size_t from = error_byte > 16 ? error_byte - 16 : 0;
  const std::string near = text.substr(std::min(from, text.size()), 32);
  if (near.find("NaN") != std::string::npos || near.find("Infinity") != std::string::npos ||
      parser_message.find("overflow") != std::string::npos) {
    message += " (the value is not finite: NaN/Infinity/overflowing numbers are not JSON numbers)";
  }
  throw DatasetError(path, message + ": " + parser_message);
}

void FieldContext::fail(const std::string& message) const {
  throw DatasetError(file, where + message);
}

const Json& require_field(const Json& object, const char* field, const FieldContext& context) {
  if (!object.is_object()) context.fail(std::string("expected an object holding ") + field);
  const auto found = object.find(field);
  if (found == object.end()) context.fail(std::string(field) + " is missing");
  return *found;
}

double finite_number(const Json& value, const char* field, const FieldContext& context) {
  if (!value.is_number()) {
    context.fail(std::string(field) + " must be a number, got " + value.type_name());
  }
  const double number = value.get<double>();
  if (!std::isfinite(number)) context.fail(std::string(field) + " is not finite");
  return number;
}

int integer(const Json& value, const char* field, const FieldContext& context) {
  if (value.is_number_unsigned()) {
    // Read as unsigned: as long long, 18446744073709551615 would wrap to -1.
    const auto number = value.get<unsigned long long>();
    if (number > static_cast<unsigned long long>(std::numeric_limits<int>::max())) {
      context.fail(std::string(field) + " is out of range: " + std::to_string(number));
    }
    return static_cast<int>(number);
  }
  if (value.is_number_integer()) {
    const auto number = value.get<long long>();
    if (number < std::numeric_limits<int>::min() || number > std::numeric_limits<int>::max()) {
      context.fail(std::string(field) + " is out of range: " + std::to_string(number));
    }
    return static_cast<int>(number);
  }
  if (value.is_number_float()) {
    const double number = value.get<double>();
    if (std::isfinite(number) && number == std::floor(number) && std::abs(number) < 1e9) {
      return static_cast<int>(number);
    }
  }
  context.fail(std::string(field) + " must be an integer, got " + value.dump());
}

std::vector<double> finite_numbers(const Json& value, const char* field, size_t count,
                                   const FieldContext& context) {
  if (!value.is_array()) {
    context.fail(std::string(field) + " must be an array of " + std::to_string(count) +
                 " numbers, got " + value.type_name());
  }
  if (value.size() != count) {
    context.fail(std::string(field) + " has " + std::to_string(value.size()) +
                 " values, expected " + std::to_string(count));
  }
  std::vector<double> numbers;
  numbers.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    const Json& element = value[i];
    if (!element.is_number()) {
      context.fail(std::string(field) + "[" + std::to_string(i) + "] must be a number, got " +
                   element.type_name());
    }
    const double number = element.get<double>();
    if (!std::isfinite(number)) {
      context.fail(std::string(field) + "[" + std::to_string(i) + "] is not finite");
    }
    numbers.push_back(number);
  }
  return numbers;
}

Eigen::Matrix3d row_major_matrix(const Json& value, const char* field,
                                 const FieldContext& context) {
  const std::vector<double> numbers = finite_numbers(value, field, 9, context);
  Eigen::Matrix3d matrix;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) matrix(row, col) = numbers[3 * row + col];
  }
  return matrix;
}

bool is_rotation(const Eigen::Matrix3d& matrix, double tolerance, std::string* why) {
  const double orthonormality_error = rotation_orthonormality_error(matrix);
  if (orthonormality_error > tolerance) {
    std::ostringstream message;
    message << "not a rotation: |R^T R - I| = " << orthonormality_error << " exceeds " << tolerance;
    if (why) *why = message.str();
    return false;
  }
  // Within the tolerance det(R)^2 = det(R^T R) is within about 3 tolerance of 1, so this
  // refuses reflections (det = -1) and nothing the orthonormality check accepted otherwise.
  const double determinant = matrix.determinant();
  if (std::abs(determinant - 1.0) > 3 * tolerance) {
    std::ostringstream message;
    message << "not a rotation: det(R) = " << determinant << ", expected +1";
    if (why) *why = message.str();
    return false;
  }
  return true;
}

Eigen::Matrix3d rotation(const Json& value, const char* field, const FieldContext& context,
                         double tolerance) {
  const Eigen::Matrix3d matrix = row_major_matrix(value, field, context);
  std::string why;
  if (!is_rotation(matrix, tolerance, &why)) context.fail(std::string(field) + " is " + why);
  return matrix;
}

Eigen::Vector3d vector3(const Json& value, const char* field, const FieldContext& context) {
  const std::vector<double> numbers = finite_numbers(value, field, 3, context);
  return Eigen::Vector3d(numbers[0], numbers[1], numbers[2]);
}

void check_intrinsics(double fx, double fy, double cx, double cy, int width, int height,
                      const char* field, const FieldContext& context) {
  const auto text = [](double value) {
    std::ostringstream out;
    out << value;
    return out.str();
  };
  for (const auto& [name, focal] : {std::pair<const char*, double>{"fx", fx}, {"fy", fy}}) {
    if (!(focal >= kMinFocalLengthPx && focal <= kMaxFocalLengthPx)) {
      context.fail(std::string(field) + " " + name + " = " + text(focal) +
                   " px is outside the accepted " + text(kMinFocalLengthPx) + " to " +
                   text(kMaxFocalLengthPx) + " px (a focal length in pixels)");
    }
  }
  for (const auto& [name, centre, size] :
       {std::tuple<const char*, double, int>{"cx", cx, width}, {"cy", cy, height}}) {
    if (!(centre >= -size && centre <= 2.0 * size)) {
      context.fail(std::string(field) + " " + name + " = " + text(centre) +
                   " px is off the image by more than its size (accepted: -" +
                   std::to_string(size) + " to " + std::to_string(2 * size) + " px for " +
                   (name[1] == 'x' ? "width " : "height ") + std::to_string(size) + ")");
    }
  }
}

int key_as_id(const std::string& key, const char* what, const FieldContext& context) {
  const bool digits =
      !key.empty() && key.size() <= 9 && std::all_of(key.begin(), key.end(), [](char c) {
        return std::isdigit(static_cast<unsigned char>(c));
      });
  if (!digits) context.fail(std::string(what) + " key \"" + key + "\" is not an integer id");
  // BOP writes str(int): "09" next to "9" would name one id twice, and every lookup goes by
  // the canonical key.
  if (key.size() > 1 && key.front() == '0') {
    context.fail(std::string(what) + " key \"" + key +
                 "\" has a leading zero (ids are written as plain integers, e.g. \"" +
                 std::to_string(std::stoi(key)) + "\")");
  }
  return std::stoi(key);
}

std::string python_dumps(const Json& value) {
  switch (value.type()) {
    case Json::value_t::object: {
      std::string text = "{";
      bool first = true;
      // nlohmann's object is a std::map: keys iterate in sorted order, like sort_keys=True.
      for (const auto& [key, element] : value.items()) {
        if (!first) text += ", ";
        first = false;
        text += Json(key).dump(-1, ' ', true) + ": " + python_dumps(element);
      }
      return text + "}";
    }
    case Json::value_t::array: {
      std::string text = "[";
      for (size_t i = 0; i < value.size(); ++i) {
        if (i > 0) text += ", ";
        text += python_dumps(value[i]);
      }
      return text + "]";
    }
    default:
      // Numbers: nlohmann prints doubles in shortest round-trip form ("0.1", "1.0", "1e-05"),
      // as Python's repr does.
      return value.dump(-1, ' ', true);
  }
}

std::string bop_dump(const std::map<int, Json>& entries) {
  std::string text = "{\n";
  size_t index = 0;
  for (const auto& [id, value] : entries) {
    text += "  \"" + std::to_string(id) + "\": " + python_dumps(value);
    if (++index != entries.size()) text += ",";
    text += "\n";
  }
  return text + "}";
}

}  // namespace clutterscope::datasets::detail
