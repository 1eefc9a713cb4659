// Fuzz target: model loading, datasets::load_mesh, as every command loads a model of
// models_info.json. The file gets the extension its bytes suggest, as a dataset's models
// would: ".ply" after a "ply" magic, ".stl" after "solid" or for a binary body of at least
// 84 bytes (header + triangle count), else ".obj". A loaded mesh must keep load_mesh's
// contract: finite positions, every index in range, normals none or one per vertex.
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <cstdlib>
#include <cstring>

#include "fuzz_support.hpp"

namespace {

const char* extension_of(const std::uint8_t* data, std::size_t size) {
  const auto starts_with = [&](const char* magic) {
    return size >= std::strlen(magic) && std::memcmp(data, magic, std::strlen(magic)) == 0;
  };
  if (starts_with("ply")) return ".ply";
  if (starts_with("solid")) return ".stl";
  const bool binary = std::memchr(data, 0, size) != nullptr;
  if (binary && size >= 84) return ".stl";
  return ".obj";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace fs = std::filesystem;
  const fs::path path =
      clutterscope::fuzz::scratch_dir() / (std::string("model") + extension_of(data, size));
  clutterscope::fuzz::write_bytes(path, data, size);
  try {
    const clutterscope::datasets::Mesh mesh = clutterscope::datasets::load_mesh(path);
    const std::size_t vertices = mesh.positions.size();
    for (const auto& p : mesh.positions) {
      if (!p.allFinite()) std::abort();
    }
    for (const auto& triangle : mesh.triangles) {
      for (const auto index : triangle) {
        if (index >= vertices) std::abort();
      }
    }
    if (!mesh.normals.empty() && mesh.normals.size() != vertices) std::abort();
  } catch (const clutterscope::datasets::DatasetError&) {
  }
  std::error_code error;
  fs::remove(path, error);
  return 0;
}
