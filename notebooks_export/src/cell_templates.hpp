#pragma once

// The cell templates compiled into the library from notebooks_export/templates/ (see
// cmake/embed_files.cmake, which generates the definition of cell_templates()).

#include <string_view>
#include <vector>

namespace clutterscope::notebooks_export::detail {

struct CellTemplate {
  std::string_view file_name;  // "NN_name.md" (markdown cell) or "NN_name.py" (code cell)
  std::string_view text;       // with {{PLACEHOLDER}} fields
};

// In notebook order (sorted by file name).
const std::vector<CellTemplate>& cell_templates();

}  // namespace clutterscope::notebooks_export::detail
