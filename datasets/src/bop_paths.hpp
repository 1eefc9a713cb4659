#pragma once

// Path pieces of the BOP layout shared by the reader and the writer.

#include <cstdio>
#include <string>

namespace clutterscope::datasets::detail {

// BOP folder and file names number scenes, images and objects with six digits ("000012").
inline std::string six_digits(int id) {
  char text[32];
  std::snprintf(text, sizeof(text), "%06d", id);
  return text;
}

}  // namespace clutterscope::datasets::detail
