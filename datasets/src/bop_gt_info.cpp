#include <clutterscope/datasets/bop_gt_info.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <string>

#include "bop_json.hpp"

namespace clutterscope::datasets {

using detail::FieldContext;
using detail::Json;

std::map<int, std::vector<double>> parse_scene_gt_visib_fract(std::string_view text,
                                                              const std::filesystem::path& path,
                                                              int scene_id) {
  Json info;
  try {
    info = Json::parse(text);
  } catch (const Json::exception& error) {
    throw DatasetError(path, location(scene_id) + "malformed JSON: " + error.what());
  }
  if (!info.is_object()) {
    throw DatasetError(path, location(scene_id) + "expected an object of image id -> list, got " +
                                 info.type_name());
  }
  std::map<int, std::vector<double>> images;
  for (const auto& item : info.items()) {
    const int im_id =
        detail::key_as_id(item.key(), "image", FieldContext{path, location(scene_id)});
    const FieldContext image_context{path, location(scene_id, im_id)};
    if (!item.value().is_array()) {
      image_context.fail("expected a list of GT instances, got " +
                         std::string(item.value().type_name()));
    }
    std::vector<double>& fractions = images[im_id];
    for (std::size_t k = 0; k < item.value().size(); ++k) {
      const Json& instance = item.value()[k];
      const FieldContext context{path, location(scene_id, im_id, static_cast<int>(k))};
      if (!instance.is_object()) context.fail("expected an object, got " + instance.dump());
      const double fraction = detail::finite_number(
          detail::require_field(instance, "visib_fract", context), "visib_fract", context);
      if (!(fraction >= 0 && fraction <= 1)) {
        context.fail("visib_fract must be in [0, 1], got " + std::to_string(fraction));
      }
      fractions.push_back(fraction);
    }
  }
  return images;
}

std::map<int, std::vector<double>> read_scene_gt_visib_fract(const std::filesystem::path& path,
                                                             int scene_id) {
  return parse_scene_gt_visib_fract(read_file(path), path, scene_id);
}

}  // namespace clutterscope::datasets
