#include "mesh_checks.hpp"

#include <charconv>
#include <clutterscope/datasets/errors.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace clutterscope::datasets::detail {

namespace {

// The file's lines, each without its line break; refuses lines over kMaxTextLine.
template <typename Visit>
void for_each_line(const std::filesystem::path& path, std::string_view bytes, Visit visit) {
  std::size_t offset = 0;
  for (std::size_t number = 1; offset < bytes.size(); ++number) {
    std::size_t end = bytes.find('\n', offset);
    if (end == std::string_view::npos) end = bytes.size();
    std::string_view line = bytes.substr(offset, end - offset);
    if (line.size() > kMaxTextLine) {
      throw DatasetError(path, "line " + std::to_string(number) + ": longer than " +
                                   std::to_string(kMaxTextLine) + " characters");
    }
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    visit(number, line);
    offset = end + 1;
  }
}

bool finite_number(std::string_view token) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  double value = 0;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && ptr == token.data() + token.size() && std::isfinite(value);
}

}  // namespace

std::vector<std::string_view> tokens_of(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

void check_obj(const std::filesystem::path& path, std::string_view bytes) {
  // First pass: how many positions, texture coordinates and normals the file declares.
  std::int64_t totals[3] = {0, 0, 0};
  for_each_line(path, bytes, [&](std::size_t number, std::string_view line) {
    const std::vector<std::string_view> tokens = tokens_of(line);
    if (tokens.empty()) return;
    const std::string where = "line " + std::to_string(number) + ": ";
    if (tokens[0] == "v") {
      if (tokens.size() < 4)
        throw DatasetError(path, where + "vertex with fewer than 3 coordinates");
      for (std::size_t k = 1; k < tokens.size(); ++k) {
        if (!finite_number(tokens[k])) {
          throw DatasetError(path, where + "vertex coordinate '" + std::string(tokens[k]) +
                                       "' is not a finite number");
        }
      }
      ++totals[0];
    } else if (tokens[0] == "vt") {
      ++totals[1];
    } else if (tokens[0] == "vn") {
      ++totals[2];
    }
  });
  // Second pass: every index in range.
  std::int64_t seen[3] = {0, 0, 0};
  const char* kinds[3] = {"vertex", "texture coordinate", "normal"};
  const char* plurals[3] = {"vertices", "texture coordinates", "normals"};
  for_each_line(path, bytes, [&](std::size_t number, std::string_view line) {
    const std::vector<std::string_view> tokens = tokens_of(line);
    if (tokens.empty()) return;
    if (tokens[0] == "v") ++seen[0];
    if (tokens[0] == "vt") ++seen[1];
    if (tokens[0] == "vn") ++seen[2];
    if (tokens[0] != "f" && tokens[0] != "l" && tokens[0] != "p") return;
    const std::string where = "line " + std::to_string(number) + ": ";
    for (std::size_t k = 1; k < tokens.size(); ++k) {
      std::string_view corner = tokens[k];
      for (int slot = 0; slot < 3 && !corner.empty(); ++slot) {
        const std::size_t slash = corner.find('/');
        const std::string_view field = corner.substr(0, slash);
        corner = slash == std::string_view::npos ? std::string_view() : corner.substr(slash + 1);
        if (field.empty() && slot > 0) continue;  // v//vn
        std::int64_t index = 0;
        const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), index);
        if (ec != std::errc() || ptr != field.data() + field.size() || index == 0) {
          throw DatasetError(path,
                             where + "'" + std::string(tokens[k]) + "' is not a valid face corner");
        }
        const std::int64_t resolved = index < 0 ? seen[slot] + index + 1 : index;
        if (resolved < 1 || resolved > totals[slot]) {
          throw DatasetError(path, where + kinds[slot] + " index " + std::to_string(index) +
                                       " out of range (" +
                                       std::to_string(index < 0 ? seen[slot] : totals[slot]) + " " +
                                       plurals[slot] + ")");
        }
      }
    }
  });
}

void check_stl(const std::filesystem::path& path, std::string_view bytes) {
  if (bytes.size() >= 84) {
    std::uint32_t triangles = 0;
    std::memcpy(&triangles, bytes.data() + 80, sizeof(triangles));
    if (84 + 50 * std::uint64_t{triangles} == bytes.size()) return;  // binary
  }
  std::size_t start = 0;
  while (start < bytes.size() && (bytes[start] == ' ' || bytes[start] == '\t')) ++start;
  if (bytes.substr(start, 5) != "solid") {
    std::string expected = "at least 84";
    if (bytes.size() >= 84) {
      std::uint32_t triangles = 0;
      std::memcpy(&triangles, bytes.data() + 80, sizeof(triangles));
      expected = std::to_string(84 + 50 * std::uint64_t{triangles}) + " (84 + 50 x " +
                 std::to_string(triangles) + " triangles)";
    }
    throw DatasetError(
        path, "binary STL of " + std::to_string(bytes.size()) + " bytes, expected " + expected);
  }
  int vertices_in_facet = -1;  // -1: outside a facet
  for_each_line(path, bytes, [&](std::size_t number, std::string_view line) {
    const std::vector<std::string_view> tokens = tokens_of(line);
    if (tokens.empty()) return;
    const std::string where = "line " + std::to_string(number) + ": ";
    // assimp's ASCII STL importer leaks or misreads what strays from this grammar (a fuzzed
    // "facet ;normal" leaked its mesh), so every line must be one of the format's keywords.
    if (tokens[0] == "facet") {
      if (vertices_in_facet >= 0) throw DatasetError(path, where + "facet inside a facet");
      if (tokens.size() != 5 || tokens[1] != "normal")
        throw DatasetError(path, where + "expected 'facet normal nx ny nz'");
      for (std::size_t k = 2; k < 5; ++k) {
        if (!finite_number(tokens[k])) {
          throw DatasetError(
              path, where + "facet normal '" + std::string(tokens[k]) + "' is not a finite number");
        }
      }
      vertices_in_facet = 0;
    } else if (tokens[0] == "outer" || tokens[0] == "endloop") {
      if (vertices_in_facet < 0)
        throw DatasetError(path, where + std::string(tokens[0]) + " outside a facet");
      if (tokens[0] == "outer" && (tokens.size() != 2 || tokens[1] != "loop"))
        throw DatasetError(path, where + "expected 'outer loop'");
    } else if (tokens[0] == "solid" || tokens[0] == "endsolid") {
      if (vertices_in_facet >= 0)
        throw DatasetError(path, where + std::string(tokens[0]) + " inside a facet");
      // assimp takes the one token after "solid" as the name and reads the rest of the line
      // as the body, skipping unknown bytes one at a time: a keyword there starts a facet this
      // grammar never checked (a fuzzed "solid box\016 facet normal 0 lid box" leaked).
      if (tokens[0] == "solid") {
        for (std::size_t k = 2; k < tokens.size(); ++k) {
          for (const char* keyword : {"facet", "outer", "vertex", "endloop", "endsolid"}) {
            if (tokens[k].find(keyword) != std::string_view::npos) {
              throw DatasetError(path, where + "the solid's name is one word; '" +
                                           std::string(tokens[k]) + "' after it holds '" + keyword +
                                           "'");
            }
          }
        }
      }
    } else if (tokens[0] == "vertex") {
      if (tokens.size() != 4) throw DatasetError(path, where + "vertex needs 3 coordinates");
      for (std::size_t k = 1; k < 4; ++k) {
        if (!finite_number(tokens[k])) {
          throw DatasetError(path, where + "vertex coordinate '" + std::string(tokens[k]) +
                                       "' is not a finite number");
        }
      }
      if (vertices_in_facet < 0) throw DatasetError(path, where + "vertex outside a facet");
      ++vertices_in_facet;
    } else if (tokens[0] == "endfacet") {
      if (vertices_in_facet != 3) {
        throw DatasetError(path, where + "facet with " + std::to_string(vertices_in_facet) +
                                     " vertices, expected 3");
      }
      vertices_in_facet = -1;
    } else {
      throw DatasetError(path,
                         where + "'" + std::string(tokens[0]) + "' is not a keyword of ASCII STL");
    }
  });
  if (vertices_in_facet >= 0) throw DatasetError(path, "file ends inside a facet");
}

}  // namespace clutterscope::datasets::detail
