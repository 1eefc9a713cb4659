// BOP test-target lists (bop_toolkit docs/bop_datasets_format.md; written by
// scripts/create_test_targets.py): test_targets_bop19.json holds {scene_id, im_id, obj_id,
// inst_count} per (image, object) for the localisation evaluation, test_targets_bop24.json
// holds {scene_id, im_id} per image for the detection evaluation.

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <fstream>
#include <sstream>

#include "bop_json.hpp"

namespace clutterscope::datasets {

using detail::FieldContext;
using detail::Json;

namespace {

int non_negative_id(const Json& entry, const char* field, const FieldContext& context) {
  const int value = detail::integer(detail::require_field(entry, field, context), field, context);
  if (value < 0) context.fail(std::string(field) + " must be >= 0, got " + std::to_string(value));
  return value;
}

}  // namespace

TestTargets parse_test_targets(const std::string& text, const std::filesystem::path& path) {
  Json json;
  try {
    json = Json::parse(text);
  } catch (const Json::exception& error) {
    throw DatasetError(path, std::string("malformed JSON: ") + error.what());
  }
  if (!json.is_array()) {
    throw DatasetError(path, std::string("expected a JSON list of test targets ({scene_id, im_id"
                                         "[, obj_id, inst_count]}), got ") +
                                 json.type_name());
  }
  TestTargets targets;
  for (std::size_t k = 0; k < json.size(); ++k) {
    const Json& entry = json[k];
    const FieldContext context{path, "target " + std::to_string(k) + ": "};
    if (!entry.is_object()) context.fail("must be an object, got " + entry.dump());
    const int scene_id = non_negative_id(entry, "scene_id", context);
    const int im_id = non_negative_id(entry, "im_id", context);
    const FieldContext located{path,
                               "target " + std::to_string(k) + ", " + location(scene_id, im_id)};
    const bool has_obj = entry.contains("obj_id");
    if (has_obj != entry.contains("inst_count")) {
      located.fail("obj_id and inst_count must be given together (bop19) or not at all (bop24)");
    }
    if (k == 0) {
      targets.per_object = has_obj;
    } else if (has_obj != targets.per_object) {
      located.fail(std::string(has_obj ? "has" : "lacks") +
                   " obj_id/inst_count unlike target 0: bop19 (per object) and bop24 (per "
                   "image) entries cannot be mixed");
    }
    const auto inserted = targets.images.try_emplace({scene_id, im_id});
    if (!has_obj) {
      if (!inserted.second) located.fail("image listed twice");
      continue;
    }
    const int obj_id = non_negative_id(entry, "obj_id", located);
    const int inst_count = detail::integer(entry["inst_count"], "inst_count", located);
    if (inst_count < 1) located.fail("inst_count must be >= 1, got " + std::to_string(inst_count));
    if (!inserted.first->second.emplace(obj_id, inst_count).second) {
      located.fail("obj_id " + std::to_string(obj_id) + " listed twice for this image");
    }
  }
  return targets;
}

TestTargets read_test_targets(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    throw DatasetError(path, "test targets file is missing");
  }
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw DatasetError(path, "cannot open file for reading");
  std::stringstream buffer;
  buffer << stream.rdbuf();
  return parse_test_targets(buffer.str(), path);
}

}  // namespace clutterscope::datasets
