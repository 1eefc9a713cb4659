#pragma once

// Checks that make an OBJ or STL file safe to hand to assimp (internal to the datasets library).

#include <filesystem>
#include <string_view>
#include <vector>

namespace clutterscope::datasets::detail {

// Lines of OBJ and ASCII STL files longer than this are refused.
inline constexpr std::size_t kMaxTextLine = 1 << 16;

// The words of a text line, split at spaces and tabs (the separators of PLY headers, OBJ and
// ASCII STL).
std::vector<std::string_view> tokens_of(std::string_view line);

// OBJ: bounded lines; `v` lines hold 3 or more finite numbers; every index of `f`, `l` and
// `p` lines (v, v/vt, v//vn, v/vt/vn; negative ones relative to the vertices read so far) is
// in range of the `v`, `vt` and `vn` lines of the file. Throws DatasetError naming
// the line.
void check_obj(const std::filesystem::path& path, std::string_view bytes);

// STL: a binary file is exactly 84 + 50 x (its triangle count) bytes; otherwise it must be
// ASCII ("solid ..."), with bounded lines, `vertex` followed by 3 finite numbers and 3 vertices
// in each facet. Throws DatasetError.
void check_stl(const std::filesystem::path& path, std::string_view bytes);

}  // namespace clutterscope::datasets::detail
