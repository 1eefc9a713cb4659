#include <algorithm>
#include <atomic>
#include <clutterscope/batch/dataset_selection.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <iostream>
#include <thread>

namespace clutterscope::batch {

namespace fs = std::filesystem;

namespace {

// Ranges wider than this are a typo, not a selection.
constexpr long kMaxRangeSpan = 10'000'000;

int parse_id(const std::string& text, const std::string& option, const std::string& whole) {
  if (text.empty() || text.size() > 9 ||
      text.find_first_not_of("0123456789") != std::string::npos) {
    throw UsageError(option + ": '" + text + "' in '" + whole +
                     "' is not an id (expected non-negative ids and ranges, e.g. 1,2,5-7)");
  }
  return std::stoi(text);
}

}  // namespace

IdSelection parse_id_selection(const std::string& text, const std::string& option) {
  IdSelection selection;
  if (text.empty()) return selection;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string token = text.substr(start, comma - start);
    const std::size_t dash = token.find('-');
    if (dash == std::string::npos) {
      selection.ids.push_back(parse_id(token, option, text));
    } else {
      const int first = parse_id(token.substr(0, dash), option, text);
      const int last = parse_id(token.substr(dash + 1), option, text);
      if (last < first || static_cast<long>(last) - first > kMaxRangeSpan) {
        throw UsageError(option + ": range '" + token + "' must be FIRST-LAST with FIRST <= LAST" +
                         " and at most " + std::to_string(kMaxRangeSpan) + " ids");
      }
      selection.ranges.emplace_back(first, last);
    }
    start = comma + 1;
  }
  return selection;
}

std::vector<int> parse_id_list(const std::string& text, const std::string& option) {
  const IdSelection selection = parse_id_selection(text, option);
  std::vector<int> ids = selection.ids;
  for (const auto& [first, last] : selection.ranges) {
    for (int id = first; id <= last; ++id) ids.push_back(id);
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

std::string format_id_list(const std::vector<int>& ids) {
  std::string text;
  for (std::size_t first = 0; first < ids.size();) {
    std::size_t last = first;
    while (last + 1 < ids.size() && ids[last + 1] == ids[last] + 1) ++last;
    if (!text.empty()) text += ',';
    text += std::to_string(ids[first]);
    if (last > first) text += "-" + std::to_string(ids[last]);
    first = last + 1;
  }
  return text;
}

std::vector<int> select_ids(const IdSelection& selection, const std::vector<int>& existing,
                            const std::string& what, const std::filesystem::path& file) {
  if (selection.selects_all()) return existing;
  // The ids there are, at most about 60 characters of them.
  const auto available = [&existing] {
    const std::string all = format_id_list(existing);
    if (all.size() <= 60) return all.empty() ? std::string("none") : all;
    return all.substr(0, all.rfind(',', 60)) + ",... (" + std::to_string(existing.size()) + " ids)";
  };
  std::vector<int> chosen;
  for (const int id : selection.ids) {
    if (!std::binary_search(existing.begin(), existing.end(), id)) {
      throw datasets::DatasetError(file, "unknown " + what + " " + std::to_string(id) +
                                             " (there are " + what + "s " + available() + ")");
    }
    chosen.push_back(id);
  }
  for (const auto& [first, last] : selection.ranges) {
    const auto begin = std::lower_bound(existing.begin(), existing.end(), first);
    const auto end = std::upper_bound(existing.begin(), existing.end(), last);
    if (begin == end) {
      throw datasets::DatasetError(file, what + " range " + std::to_string(first) + "-" +
                                             std::to_string(last) + " selects no " + what +
                                             " (there are " + what + "s " + available() + ")");
    }
    chosen.insert(chosen.end(), begin, end);
  }
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
  return chosen;
}

std::vector<datasets::ImageKey> list_selected_images(const datasets::BopDataset& dataset,
                                                     const DatasetOptions& options) {
  datasets::DatasetSelection selection;
  selection.splits = {split_folder(options)};
  const fs::path split_path = fs::path(options.dataset) / selection.splits.front();
  const IdSelection scenes = parse_id_selection(options.scenes, "--scenes");
  if (!scenes.selects_all()) {
    selection.scene_ids =
        select_ids(scenes, dataset.scene_ids(selection.splits.front()), "scene", split_path);
  }
  const IdSelection images = parse_id_selection(options.images, "--images");
  if (images.ranges.empty()) {
    selection.image_ids = images.ids;  // each must exist: list_images names the missing one
    return dataset.list_images(selection);
  }
  // Ranges select among the images the selected scenes have (and the targets keep).
  std::vector<datasets::ImageKey> keys = dataset.list_images(selection);
  std::vector<int> existing;
  for (const datasets::ImageKey& key : keys) existing.push_back(key.im_id);
  std::sort(existing.begin(), existing.end());
  existing.erase(std::unique(existing.begin(), existing.end()), existing.end());
  const std::vector<int> chosen = select_ids(images, existing, "image", split_path);
  keys.erase(std::remove_if(keys.begin(), keys.end(),
                            [&chosen](const datasets::ImageKey& key) {
                              return !std::binary_search(chosen.begin(), chosen.end(), key.im_id);
                            }),
             keys.end());
  return keys;
}

std::string split_folder(const DatasetOptions& options) {
  return options.split_type.empty() ? options.split : options.split + "_" + options.split_type;
}

datasets::DatasetSelection selection_of(const DatasetOptions& options) {
  datasets::DatasetSelection selection;
  selection.splits = {split_folder(options)};
  selection.scene_ids = parse_id_list(options.scenes, "--scenes");
  selection.image_ids = parse_id_list(options.images, "--images");
  return selection;
}

void warn_if_more_jobs_than_cores(int jobs) {
  const unsigned cores = std::thread::hardware_concurrency();
  static std::atomic<bool> warned{false};
  if (cores == 0 || jobs <= static_cast<int>(cores) || warned.exchange(true)) return;
  std::cerr << "warning: --jobs " << jobs << " is more than the " << cores
            << " cores of this machine: workers beyond that only compete for them (and each "
               "holds a render context); continuing\n";
}

BatchOptions batch_options_of(const DatasetOptions& options, const std::string& label) {
  warn_if_more_jobs_than_cores(options.jobs);
  BatchOptions batch;
  batch.out_dir = options.out;
  batch.jobs = options.jobs;
  if (!options.shard.empty()) batch.shard = parse_shard(options.shard);
  batch.keep_going = options.keep_going;
  batch.quiet = options.quiet;
  batch.progress_label = label;
  return batch;
}

datasets::BopDataset open_dataset(const DatasetOptions& options) {
  datasets::BopOpenOptions open;
  open.models_dir = options.models_dir;
  open.camera_type = options.split_type;
  std::string why;
  if (!open.IsValid(&why)) throw UsageError("--models-dir/--split-type: " + why);
  datasets::BopDataset dataset = datasets::BopDataset::open(options.dataset, open);
  if (!options.targets.empty()) {
    dataset.attach_targets(datasets::read_test_targets(options.targets), options.targets);
  }
  return dataset;
}

nlohmann::json input_checks_of(const datasets::SceneView& view) {
  std::int64_t off = 0;
  double worst = 0.0;
  for (const datasets::GtInstance& object : view.objects) {
    const double error = datasets::rotation_orthonormality_error(object.model_to_camera.linear());
    if (error > datasets::kRotationReportThreshold) ++off;
    worst = std::max(worst, error);
  }
  return {{"rotations_off", off}, {"max_rotation_error", worst}};
}

nlohmann::json no_depth_values_entry(const datasets::ImageKey& key, const fs::path& depth_file,
                                     const fs::path& dataset_root) {
  const fs::path relative = depth_file.lexically_relative(dataset_root);
  const bool inside = !relative.empty() && *relative.begin() != "..";
  return {{"split", key.split},
          {"scene_id", key.scene_id},
          {"im_id", key.im_id},
          {"depth_file", (inside ? relative : depth_file).generic_string()}};
}

std::string no_depth_values_warning(const nlohmann::json& entry, const std::string& consequence) {
  return "warning: " + entry.at("depth_file").get<std::string>() + ": " +
         datasets::location(entry.at("scene_id").get<int>(), entry.at("im_id").get<int>()) +
         "the depth image has no value > 0 (no depth at all); " + consequence;
}

void InputCheckTotals::add(const nlohmann::json& image_checks) {
  rotations_off_orthonormal_ += image_checks.at("rotations_off").get<std::int64_t>();
  max_rotation_error_ =
      std::max(max_rotation_error_, image_checks.at("max_rotation_error").get<double>());
  const auto no_depth = image_checks.find(kNoDepthValuesKey);
  if (no_depth == image_checks.end()) return;
  ++images_without_depth_values_;
  if (listed_without_depth_values_.size() < kListedImages) {
    listed_without_depth_values_.push_back(*no_depth);
  }
}

nlohmann::json InputCheckTotals::to_json() const {
  nlohmann::json json = {
      {"rotations_off_orthonormal_1e-6", rotations_off_orthonormal_},
      {"max_rotation_orthonormality_error", max_rotation_error_},
      {"note",
       "GT rotations (cam_R_m2c) are used as stored, as bop_toolkit does; accepted up to "
       "|R^T R - I| = 0.02, refused beyond"}};
  if (depth_values_checked_) {
    json["images_without_depth_values"] = images_without_depth_values_;
    json["images_without_depth_values_listed"] = listed_without_depth_values_;
    json["depth_values_note"] =
        "images whose depth PNG has no value > 0, in item order (the first " +
        std::to_string(kListedImages) +
        " listed, each named on stderr): every pixel lacks depth, so bop19 counts every object "
        "pixel as visible (bop_toolkit's rule: visib_fract 1.0 where the object lies inside the "
        "image) and bop18 none (0.0)";
  }
  return json;
}

nlohmann::json dataset_fingerprint(const DatasetOptions& options) {
  std::error_code error;
  fs::path dataset = fs::weakly_canonical(fs::absolute(options.dataset), error);
  if (error) dataset = fs::absolute(options.dataset).lexically_normal();
  nlohmann::json fingerprint = {
      {"dataset", dataset.string()},
      {"split", options.split},
      {"scenes", format_id_list(parse_id_list(options.scenes, "--scenes"))},
      {"images", format_id_list(parse_id_list(options.images, "--images"))}};
  if (!options.split_type.empty()) fingerprint["split_type"] = options.split_type;
  if (options.models_dir != "models") fingerprint["models_dir"] = options.models_dir;
  if (!options.targets.empty()) {
    fs::path targets = fs::weakly_canonical(fs::absolute(options.targets), error);
    if (error) targets = fs::absolute(options.targets).lexically_normal();
    fingerprint["targets"] = targets.string();
  }
  return fingerprint;
}

void add_depth_check_fingerprint(const datasets::DepthCheckOptions& options,
                                 nlohmann::json* fingerprint) {
  if (options.depth_scale) (*fingerprint)["depth_scale"] = *options.depth_scale;
  if (!options.check) (*fingerprint)["depth_check"] = false;
}

}  // namespace clutterscope::batch
