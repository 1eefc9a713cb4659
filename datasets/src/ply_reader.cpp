#include "ply_reader.hpp"

#include <algorithm>
#include <charconv>
#include <clutterscope/datasets/errors.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "mesh_checks.hpp"

namespace clutterscope::datasets::detail {

namespace {

enum class Format { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

enum class Type { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

std::optional<Type> parse_type(std::string_view name) {
  if (name == "char" || name == "int8") return Type::kInt8;
  if (name == "uchar" || name == "uint8") return Type::kUint8;
  if (name == "short" || name == "int16") return Type::kInt16;
  if (name == "ushort" || name == "uint16") return Type::kUint16;
  if (name == "int" || name == "int32") return Type::kInt32;
  if (name == "uint" || name == "uint32") return Type::kUint32;
  if (name == "float" || name == "float32") return Type::kFloat32;
  if (name == "double" || name == "float64") return Type::kFloat64;
  return std::nullopt;
}

std::size_t size_of(Type type) {
  switch (type) {
    case Type::kInt8:
    case Type::kUint8:
      return 1;
    case Type::kInt16:
    case Type::kUint16:
      return 2;
    case Type::kInt32:
    case Type::kUint32:
    case Type::kFloat32:
      return 4;
    case Type::kFloat64:
      return 8;
  }
  return 8;
}

bool is_integer(Type type) { return type != Type::kFloat32 && type != Type::kFloat64; }

struct Property {
  std::string name;
  Type type = Type::kFloat32;      // the value type; for a list, its items
  std::optional<Type> count_type;  // set for lists
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
};

struct Header {
  Format format = Format::kAscii;
  std::vector<Element> elements;
  std::size_t body_offset = 0;
};

class PlyParser {
 public:
  PlyParser(const std::filesystem::path& path, std::string_view bytes)
      : path_(path), bytes_(bytes) {}

  [[noreturn]] void fail(const std::string& what) const { throw DatasetError(path_, what); }

  Header parse_header() {
    Header header;
    bool have_format = false;
    std::size_t offset = 0;
    for (int line_number = 1;; ++line_number) {
      const std::string where = "header line " + std::to_string(line_number) + ": ";
      if (offset >= kPlyMaxHeaderBytes) {
        fail("header: no end_header in the first " + std::to_string(kPlyMaxHeaderBytes) + " bytes");
      }
      const std::size_t end = bytes_.find('\n', offset);
      if (end == std::string_view::npos) {
        fail("header: file ends inside the header (no end_header), after " +
             std::to_string(bytes_.size()) + " bytes");
      }
      std::string_view line = bytes_.substr(offset, end - offset);
      if (line.size() > kPlyMaxHeaderLine) {
        fail(where + "longer than " + std::to_string(kPlyMaxHeaderLine) + " characters");
      }
      offset = end + 1;
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      const std::vector<std::string_view> tokens = tokens_of(line);
      if (line_number == 1) {
        if (line != "ply") fail("not a PLY file (the first line is not 'ply')");
        continue;
      }
      if (tokens.empty()) continue;
      const std::string_view keyword = tokens[0];
      if (keyword == "comment" || keyword == "obj_info") continue;
      if (keyword == "end_header") {
        if (!have_format) fail("header: no format line");
        header.body_offset = offset;
        return header;
      }
      if (keyword == "format") {
        if (tokens.size() != 3) fail(where + "expected 'format <type> 1.0'");
        if (tokens[1] == "ascii") {
          header.format = Format::kAscii;
        } else if (tokens[1] == "binary_little_endian") {
          header.format = Format::kBinaryLittleEndian;
        } else if (tokens[1] == "binary_big_endian") {
          header.format = Format::kBinaryBigEndian;
        } else {
          fail(where + "unknown format '" + std::string(tokens[1]) +
               "' (ascii, binary_little_endian, binary_big_endian)");
        }
        if (tokens[2] != "1.0") {
          fail(where + "unsupported PLY version '" + std::string(tokens[2]) + "' (1.0)");
        }
        have_format = true;
      } else if (keyword == "element") {
        if (tokens.size() != 3) fail(where + "expected 'element <name> <count>'");
        Element element;
        element.name = std::string(tokens[1]);
        const char* first = tokens[2].data();
        const char* last = first + tokens[2].size();
        const auto [ptr, ec] = std::from_chars(first, last, element.count);
        if (ec != std::errc() || ptr != last) {
          fail(where + "element " + element.name + ": count '" + std::string(tokens[2]) +
               "' is not a non-negative integer");
        }
        for (const Element& other : header.elements) {
          if (other.name == element.name) fail(where + "element " + element.name + " twice");
        }
        header.elements.push_back(std::move(element));
      } else if (keyword == "property") {
        if (header.elements.empty()) fail(where + "property before any element");
        Element& element = header.elements.back();
        Property property;
        if (tokens.size() == 5 && tokens[1] == "list") {
          const std::optional<Type> count_type = parse_type(tokens[2]);
          const std::optional<Type> item_type = parse_type(tokens[3]);
          if (!count_type || !is_integer(*count_type)) {
            fail(where + "list count type '" + std::string(tokens[2]) + "' is not an integer type");
          }
          if (!item_type) fail(where + "unknown type '" + std::string(tokens[3]) + "'");
          property.count_type = count_type;
          property.type = *item_type;
          property.name = std::string(tokens[4]);
        } else if (tokens.size() == 3) {
          const std::optional<Type> type = parse_type(tokens[1]);
          if (!type) fail(where + "unknown type '" + std::string(tokens[1]) + "'");
          property.type = *type;
          property.name = std::string(tokens[2]);
        } else {
          fail(where + "expected 'property <type> <name>' or 'property list <type> <type> <name>'");
        }
        element.properties.push_back(std::move(property));
      } else {
        fail(where + "unknown keyword '" + std::string(keyword) + "'");
      }
    }
  }

  // Element counts against the body, before anything is allocated.
  void check_counts(const Header& header) const {
    const std::uint64_t body = bytes_.size() - header.body_offset;
    const bool ascii = header.format == Format::kAscii;
    std::uint64_t used = 0;  // bytes (binary) or numbers (ascii) the elements so far need
    for (const Element& element : header.elements) {
      if (element.count == 0) continue;
      if (element.properties.empty()) {
        fail("header: element " + element.name + " has " + std::to_string(element.count) +
             " records but no properties");
      }
      std::uint64_t per_record = 0;
      for (const Property& property : element.properties) {
        per_record += ascii ? 1 : size_of(property.count_type.value_or(property.type));
      }
      const std::uint64_t left = body - std::min(body, used);
      if (element.count > left / per_record) {
        const std::string needed =
            element.count > std::numeric_limits<std::uint64_t>::max() / per_record
                ? "more than " + std::to_string(std::numeric_limits<std::uint64_t>::max())
                : std::to_string(element.count * per_record);
        fail("header: element " + element.name + " " + std::to_string(element.count) + " needs " +
             (ascii ? "at least " + needed + " numbers" : needed + " bytes") + ", file body has " +
             std::to_string(left) + (used > 0 ? " bytes left" : " bytes"));
      }
      used += element.count * per_record;
    }
  }

  // --- body reading -------------------------------------------------------------------------

  void start_body(const Header& header) {
    format_ = header.format;
    position_ = header.body_offset;
  }
  // bop_toolkit parses ASCII coordinates with Python's float(), i.e. as double.
  void read_ascii_floats_as_double() { ascii_floats_as_double_ = true; }
  void set_record(const std::string& element, std::uint64_t index) {
    element_ = &element;
    record_ = index;
  }
  std::string where() const { return *element_ + " " + std::to_string(record_) + ": "; }

  // One scalar of the given type, as a double (exact for every PLY type but float64, which is
  // read as is).
  double scalar(Type type, const std::string& property) {
    if (format_ == Format::kAscii) return ascii_scalar(type, property);
    const std::size_t size = size_of(type);
    if (bytes_.size() - position_ < size) {
      fail(where() + "file ends inside the record (property " + property + ")");
    }
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + position_, size);
    position_ += size;
    if (format_ == Format::kBinaryBigEndian) std::reverse(raw, raw + size);
    switch (type) {
      case Type::kInt8: {
        std::int8_t v;
        std::memcpy(&v, raw, 1);
        return v;
      }
      case Type::kUint8:
        return raw[0];
      case Type::kInt16: {
        std::int16_t v;
        std::memcpy(&v, raw, 2);
        return v;
      }
      case Type::kUint16: {
        std::uint16_t v;
        std::memcpy(&v, raw, 2);
        return v;
      }
      case Type::kInt32: {
        std::int32_t v;
        std::memcpy(&v, raw, 4);
        return v;
      }
      case Type::kUint32: {
        std::uint32_t v;
        std::memcpy(&v, raw, 4);
        return v;
      }
      case Type::kFloat32: {
        float v;
        std::memcpy(&v, raw, 4);
        return v;
      }
      case Type::kFloat64: {
        double v;
        std::memcpy(&v, raw, 8);
        return v;
      }
    }
    return 0;
  }

  // A list's length, checked against what is left of the file.
  std::uint64_t list_count(const Property& property) {
    const double count = scalar(*property.count_type, property.name);
    if (!(count >= 0)) {
      fail(where() + "list " + property.name + " has a negative length (" +
           std::to_string(static_cast<long long>(count)) + ")");
    }
    const auto n = static_cast<std::uint64_t>(count);
    const std::uint64_t left = bytes_.size() - position_;
    // Binary: each item takes its size; ascii: a number and a separator.
    const std::uint64_t most =
        format_ == Format::kAscii ? left / 2 + 1 : left / size_of(property.type);
    if (n > most) {
      fail(where() + "list " + property.name + " of " + std::to_string(n) +
           " items is longer than the rest of the file (" + std::to_string(left) + " bytes)");
    }
    return n;
  }

  void skip(const Property& property) {
    if (property.count_type) {
      const std::uint64_t n = list_count(property);
      if (format_ == Format::kAscii) {
        for (std::uint64_t i = 0; i < n; ++i) next_token(property.name);
      } else {
        position_ += n * size_of(property.type);  // fits: list_count checked it
      }
    } else if (format_ == Format::kAscii) {
      next_token(property.name);
    } else {
      scalar(property.type, property.name);
    }
  }

 private:
  std::string_view next_token(const std::string& property) {
    while (position_ < bytes_.size() && is_space(bytes_[position_])) ++position_;
    const std::size_t start = position_;
    while (position_ < bytes_.size() && !is_space(bytes_[position_])) ++position_;
    if (position_ == start)
      fail(where() + "file ends inside the record (property " + property + ")");
    return bytes_.substr(start, position_ - start);
  }

  static bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
  }

  double ascii_scalar(Type type, const std::string& property) {
    std::string_view token = next_token(property);
    const std::string text(token);
    if (!token.empty() && token[0] == '+') token.remove_prefix(1);
    const char* first = token.data();
    const char* last = first + token.size();
    if (is_integer(type)) {
      long long value = 0;
      const auto [ptr, ec] = std::from_chars(first, last, value);
      if (ec != std::errc() || ptr != last) {
        fail(where() + "property " + property + ": '" + text + "' is not an integer");
      }
      return static_cast<double>(value);
    }
    if (type == Type::kFloat32 && !ascii_floats_as_double_) {
      float value = 0;
      const auto [ptr, ec] = std::from_chars(first, last, value);
      if (ec == std::errc::result_out_of_range) return std::numeric_limits<double>::infinity();
      if (ec != std::errc() || ptr != last) {
        fail(where() + "property " + property + ": '" + text + "' is not a number");
      }
      return value;
    }
    double value = 0;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec == std::errc::result_out_of_range) return std::numeric_limits<double>::infinity();
    if (ec != std::errc() || ptr != last) {
      fail(where() + "property " + property + ": '" + text + "' is not a number");
    }
    return value;
  }

  const std::filesystem::path& path_;
  std::string_view bytes_;
  Format format_ = Format::kAscii;
  std::size_t position_ = 0;
  const std::string* element_ = nullptr;
  std::uint64_t record_ = 0;
  bool ascii_floats_as_double_ = false;
};

int find_property(const Element& element, std::string_view name) {
  for (std::size_t i = 0; i < element.properties.size(); ++i) {
    if (element.properties[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

using Vec3 = std::array<float, 3>;

Vec3 minus(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

// aiVector3D::Normalize / NormalizeSafe in float, as assimp computes them.
Vec3 normalized(Vec3 v) {
  const float length = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (length > 0) {
    const float inverse = 1.0f / length;
    for (float& c : v) c *= inverse;
  }
  return v;
}

float dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// The start corner of assimp's quad fan: its concave corner, if any (TriangulateProcess).
unsigned quad_start(const std::vector<Vec3>& p, const std::uint32_t* q) {
  for (unsigned i = 0; i < 4; ++i) {
    const Vec3& v = p[q[i]];
    const Vec3 left = normalized(minus(p[q[(i + 3) % 4]], v));
    const Vec3 diag = normalized(minus(p[q[(i + 2) % 4]], v));
    const Vec3 right = normalized(minus(p[q[(i + 1) % 4]], v));
    const float angle = std::acos(dot(left, diag)) + std::acos(dot(right, diag));
    if (angle > 3.1415926538f) return i;  // AI_MATH_PI_F
  }
  return 0;
}

// A polygon of 5 or more corners is convex when the turns at all corners agree with its
// Newell normal.
bool convex(const std::vector<Vec3>& p, const std::uint32_t* polygon, std::size_t n) {
  double normal[3] = {0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& a = p[polygon[i]];
    const Vec3& b = p[polygon[(i + 1) % n]];
    normal[0] += (double(a[1]) - b[1]) * (double(a[2]) + b[2]);
    normal[1] += (double(a[2]) - b[2]) * (double(a[0]) + b[0]);
    normal[2] += (double(a[0]) - b[0]) * (double(a[1]) + b[1]);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& a = p[polygon[i]];
    const Vec3& b = p[polygon[(i + 1) % n]];
    const Vec3& c = p[polygon[(i + 2) % n]];
    const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
    const double w[3] = {double(c[0]) - b[0], double(c[1]) - b[1], double(c[2]) - b[2]};
    const double turn = (u[1] * w[2] - u[2] * w[1]) * normal[0] +
                        (u[2] * w[0] - u[0] * w[2]) * normal[1] +
                        (u[0] * w[1] - u[1] * w[0]) * normal[2];
    if (turn < 0) return false;
  }
  return true;
}

// assimp's NGON encoding: a triangle whose first corner equals the previous polygon's fan
// corner is rotated, so that it does not read as part of that polygon.
class NgonEncoder {
 public:
  void triangle(std::array<std::uint32_t, 3>& t) {
    if (t[0] == last_) {
      std::swap(t[0], t[2]);
      std::swap(t[1], t[2]);
    }
    last_ = t[0];
  }
  void quad(std::array<std::uint32_t, 3>& a, std::array<std::uint32_t, 3>& b) {
    if (a[0] == last_) {
      std::swap(a[0], a[2]);
      std::swap(a[1], a[2]);
      std::swap(b[1], b[2]);
      std::swap(b[0], b[2]);
    }
    last_ = a[0];
  }
  // A fanned polygon (assimp ear-cuts these; its own triangles are not reproduced).
  void polygon(std::uint32_t fan_corner) { last_ = fan_corner; }

 private:
  std::uint32_t last_ = std::numeric_limits<std::uint32_t>::max();
};

}  // namespace

bool is_ply(std::string_view bytes) {
  return bytes.substr(0, 4) == "ply\n" || bytes.substr(0, 5) == "ply\r\n";
}

namespace {

// Where the mesh's data sit in the header: the vertex and face elements and their properties.
struct PlyLayout {
  const Element* vertex = nullptr;
  const Element* face = nullptr;  // may be absent
  int xyz[3] = {-1, -1, -1};
  int nxyz[3] = {-1, -1, -1};
  bool has_normals = true;
  int indices = -1;  // the face element's list of vertex indices
};

PlyLayout locate_mesh_data(PlyParser& parser, const Header& header) {
  PlyLayout layout;
  for (const Element& element : header.elements) {
    if (element.name == "vertex") layout.vertex = &element;
    if (element.name == "face") layout.face = &element;
  }
  if (layout.vertex == nullptr) parser.fail("header: no element vertex");
  const Element& vertex = *layout.vertex;
  for (int k = 0; k < 3; ++k) {
    const char* names[3] = {"x", "y", "z"};
    const char* normal_names[3] = {"nx", "ny", "nz"};
    layout.xyz[k] = find_property(vertex, names[k]);
    if (layout.xyz[k] < 0 || vertex.properties[layout.xyz[k]].count_type) {
      parser.fail(std::string("header: element vertex has no scalar property ") + names[k]);
    }
    layout.nxyz[k] = find_property(vertex, normal_names[k]);
    if (layout.nxyz[k] < 0 || vertex.properties[layout.nxyz[k]].count_type) {
      layout.has_normals = false;
    }
  }
  if (vertex.count > std::numeric_limits<std::uint32_t>::max()) {
    parser.fail("header: element vertex " + std::to_string(vertex.count) +
                " has more vertices than 32-bit indices address");
  }
  if (layout.face != nullptr) {
    const Element& face = *layout.face;
    layout.indices = find_property(face, "vertex_indices");
    if (layout.indices < 0) layout.indices = find_property(face, "vertex_index");
    if (layout.indices < 0 || !face.properties[layout.indices].count_type ||
        !is_integer(face.properties[layout.indices].type)) {
      parser.fail("header: element face has no integer list vertex_indices");
    }
  }
  return layout;
}

// The body's records, in file order.
struct PlyRecords {
  std::uint32_t vertex_count = 0;
  bool has_normals = false;
  std::vector<Vec3> positions;  // file units, for triangulation as assimp does it
  std::vector<Eigen::Vector3f> normals;
  std::vector<std::uint32_t> corners;       // all faces' indices, concatenated
  std::vector<std::uint64_t> face_offsets;  // face f: corners[offsets[f], offsets[f + 1])
};

void read_vertex(PlyParser& parser, const Element& element, const PlyLayout& layout,
                 PlyRecords* records) {
  const int* xyz = layout.xyz;
  const int* nxyz = layout.nxyz;
  double values[9] = {};
  for (std::size_t p = 0; p < element.properties.size(); ++p) {
    const Property& property = element.properties[p];
    const int slot = static_cast<int>(p) == xyz[0]    ? 0
                     : static_cast<int>(p) == xyz[1]  ? 1
                     : static_cast<int>(p) == xyz[2]  ? 2
                     : !layout.has_normals            ? -1
                     : static_cast<int>(p) == nxyz[0] ? 3
                     : static_cast<int>(p) == nxyz[1] ? 4
                     : static_cast<int>(p) == nxyz[2] ? 5
                                                      : -1;
    if (slot < 0) {
      parser.skip(property);
      continue;
    }
    values[slot] = parser.scalar(property.type, property.name);
  }
  Vec3 position;
  for (int k = 0; k < 3; ++k) {
    position[k] = static_cast<float>(values[k]);
    if (!std::isfinite(position[k])) {
      parser.fail(parser.where() + "coordinate " + element.properties[xyz[k]].name +
                  " is not finite (" + std::to_string(values[k]) + ")");
    }
  }
  records->positions.push_back(position);
  if (layout.has_normals) {
    records->normals.emplace_back(static_cast<float>(values[3]), static_cast<float>(values[4]),
                                  static_cast<float>(values[5]));
  }
}

void read_face(PlyParser& parser, const Element& element, const PlyLayout& layout,
               PlyRecords* records) {
  for (std::size_t p = 0; p < element.properties.size(); ++p) {
    const Property& property = element.properties[p];
    if (static_cast<int>(p) != layout.indices) {
      parser.skip(property);
      continue;
    }
    const std::uint64_t n = parser.list_count(property);
    for (std::uint64_t i = 0; i < n; ++i) {
      const double index = parser.scalar(property.type, property.name);
      if (!(index >= 0 && index < records->vertex_count)) {
        parser.fail(parser.where() + "vertex index " +
                    std::to_string(static_cast<long long>(index)) + " out of range (" +
                    std::to_string(records->vertex_count) + " vertices)");
      }
      records->corners.push_back(static_cast<std::uint32_t>(index));
    }
    records->face_offsets.push_back(records->corners.size());
  }
}

// Counts were checked against the body, so these allocations are bounded by the file size.
PlyRecords read_records(PlyParser& parser, const Header& header, const PlyLayout& layout) {
  PlyRecords records;
  records.vertex_count = static_cast<std::uint32_t>(layout.vertex->count);
  records.has_normals = layout.has_normals;
  parser.start_body(header);
  for (const Element& element : header.elements) {
    const bool is_vertex = &element == layout.vertex;
    const bool is_face = &element == layout.face;
    if (is_vertex) {
      records.positions.reserve(records.vertex_count);
      if (layout.has_normals) records.normals.reserve(records.vertex_count);
    }
    if (is_face) records.face_offsets.assign(1, 0);
    for (std::uint64_t r = 0; r < element.count; ++r) {
      parser.set_record(element.name, r);
      if (is_vertex) {
        read_vertex(parser, element, layout, &records);
      } else if (is_face) {
        read_face(parser, element, layout, &records);
      } else {
        for (const Property& property : element.properties) parser.skip(property);
      }
    }
  }
  return records;
}

struct Triangulation {
  std::vector<std::array<std::uint32_t, 3>> triangles;
  bool has_points_or_lines = false;  // faces of fewer than 3 corners (left out)
};

// Triangulation as assimp's TriangulateProcess and SortByPType do it.
Triangulation triangulate(PlyParser& parser, const PlyRecords& records) {
  const std::vector<std::uint64_t>& offsets = records.face_offsets;
  const std::size_t face_count = offsets.empty() ? 0 : offsets.size() - 1;
  Triangulation result;
  bool has_polygons = false;
  for (std::size_t f = 0; f < face_count; ++f) {
    const std::uint64_t n = offsets[f + 1] - offsets[f];
    has_polygons = has_polygons || n > 3;
    result.has_points_or_lines = result.has_points_or_lines || n < 3;
  }
  std::vector<std::array<std::uint32_t, 3>>& triangles = result.triangles;
  NgonEncoder encoder;
  for (std::size_t f = 0; f < face_count; ++f) {
    const std::uint32_t* face = records.corners.data() + offsets[f];
    const std::size_t n = offsets[f + 1] - offsets[f];
    if (n < 3) continue;
    if (n == 3) {
      std::array<std::uint32_t, 3> t = {face[0], face[1], face[2]};
      if (has_polygons) encoder.triangle(t);
      triangles.push_back(t);
    } else if (n == 4) {
      const unsigned s = quad_start(records.positions, face);
      std::array<std::uint32_t, 3> a = {face[s], face[(s + 1) % 4], face[(s + 2) % 4]};
      std::array<std::uint32_t, 3> b = {face[s], face[(s + 2) % 4], face[(s + 3) % 4]};
      encoder.quad(a, b);
      triangles.push_back(a);
      triangles.push_back(b);
    } else {
      if (!convex(records.positions, face, n)) {
        parser.fail("face " + std::to_string(f) + ": concave polygon of " + std::to_string(n) +
                    " vertices (triangulate the model)");
      }
      for (std::size_t k = 1; k + 1 < n; ++k) {
        triangles.push_back({face[0], face[k], face[k + 1]});
      }
      encoder.polygon(face[0]);
    }
  }
  if (triangles.empty()) parser.fail("model has no triangles");
  return result;
}

// GenSmoothNormals: each vertex takes the unit normal of the last triangle using it, then
// vertices at one position share the normalised sum (assimp groups positions within 1e-4 of the
// bounding box diagonal and sums in its spatial-sort order; here exact positions, in index
// order). Nothing renders with these normals; they keep Mesh::normals full.
void smooth_normals(const std::vector<Vec3>& file_positions,
                    const std::vector<std::uint32_t>& source,
                    const std::vector<std::array<std::uint32_t, 3>>& triangles, Mesh* mesh) {
  std::vector<Vec3> face_normal(source.size(), Vec3{0, 0, 0});
  for (const auto& t : triangles) {
    const Vec3& a = file_positions[source[t[0]]];
    const Vec3 u = minus(file_positions[source[t[1]]], a);
    const Vec3 w = minus(file_positions[source[t[2]]], a);
    const Vec3 n = normalized(
        {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]});
    for (const auto index : t) face_normal[index] = n;
  }
  const WeldedVertices welded = weld_vertices(*mesh);
  std::vector<Vec3> sum(welded.positions.size(), Vec3{0, 0, 0});
  for (std::size_t v = 0; v < source.size(); ++v) {
    for (int k = 0; k < 3; ++k) sum[welded.index_of[v]][k] += face_normal[v][k];
  }
  mesh->normals.reserve(source.size());
  for (std::size_t v = 0; v < source.size(); ++v) {
    const Vec3 n = normalized(sum[welded.index_of[v]]);
    mesh->normals.emplace_back(n[0], n[1], n[2]);
  }
}

// The mesh in metres. SortByPType splits a mesh of several primitive types, copying each
// triangle's corners.
Mesh build_mesh(const PlyRecords& records, Triangulation triangulation, float scale) {
  std::vector<std::array<std::uint32_t, 3>>& triangles = triangulation.triangles;
  Mesh mesh;
  std::vector<std::uint32_t> source;  // file vertex of each mesh vertex
  if (triangulation.has_points_or_lines) {
    source.reserve(triangles.size() * 3);
    for (auto& t : triangles) {
      for (auto& index : t) {
        source.push_back(index);
        index = static_cast<std::uint32_t>(source.size() - 1);
      }
    }
  } else {
    source.resize(records.vertex_count);
    for (std::uint32_t v = 0; v < records.vertex_count; ++v) source[v] = v;
  }
  mesh.positions.reserve(source.size());
  for (const std::uint32_t v : source) {
    const Vec3& p = records.positions[v];
    mesh.positions.emplace_back(p[0] * scale, p[1] * scale, p[2] * scale);
  }
  if (records.has_normals) {
    mesh.normals.reserve(source.size());
    for (const std::uint32_t v : source) mesh.normals.push_back(records.normals[v]);
  } else {
    smooth_normals(records.positions, source, triangles, &mesh);
  }
  mesh.triangles = std::move(triangles);
  return mesh;
}

}  // namespace

Eigen::Matrix<double, 3, Eigen::Dynamic> read_ply_vertices(const std::filesystem::path& path,
                                                           std::string_view bytes, double scale) {
  PlyParser parser(path, bytes);
  const Header header = parser.parse_header();
  parser.check_counts(header);
  const PlyLayout layout = locate_mesh_data(parser, header);
  parser.read_ascii_floats_as_double();
  parser.start_body(header);
  const Element& vertex = *layout.vertex;
  Eigen::Matrix<double, 3, Eigen::Dynamic> points;
  for (const Element& element : header.elements) {
    const bool is_vertex = &element == &vertex;
    // Counts were checked against the body, so this allocation is bounded by the file size.
    if (is_vertex) points.resize(3, static_cast<Eigen::Index>(element.count));
    for (std::uint64_t r = 0; r < element.count; ++r) {
      parser.set_record(element.name, r);
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const Property& property = element.properties[p];
        const int axis = !is_vertex                             ? -1
                         : static_cast<int>(p) == layout.xyz[0] ? 0
                         : static_cast<int>(p) == layout.xyz[1] ? 1
                         : static_cast<int>(p) == layout.xyz[2] ? 2
                                                                : -1;
        if (axis < 0) {
          parser.skip(property);
          continue;
        }
        const double value = parser.scalar(property.type, property.name);
        if (!std::isfinite(value)) {
          parser.fail(parser.where() + "coordinate " + property.name + " is not finite (" +
                      std::to_string(value) + ")");
        }
        points(axis, static_cast<Eigen::Index>(r)) = value * scale;
      }
    }
    if (is_vertex) break;
  }
  return points;
}

Mesh read_ply(const std::filesystem::path& path, std::string_view bytes, float scale) {
  PlyParser parser(path, bytes);
  const Header header = parser.parse_header();
  parser.check_counts(header);
  const PlyLayout layout = locate_mesh_data(parser, header);
  const PlyRecords records = read_records(parser, header, layout);
  return build_mesh(records, triangulate(parser, records), scale);
}

}  // namespace clutterscope::datasets::detail
