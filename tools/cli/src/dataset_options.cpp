#include <algorithm>
#include <atomic>
#include <clutterscope/cli/dataset_options.hpp>
#include <iostream>
#include <thread>

namespace clutterscope::cli {

namespace fs = std::filesystem;

namespace {

// Ranges wider than this are a typo, not a selection.
constexpr long kMaxRangeSpan = 10'000'000;

int parse_id(const std::string& text, const std::string& option, const std::string& whole) {
  if (text.empty() || text.size() > 9 ||
      text.find_first_not_of("0123456789") != std::string::npos) {
    throw batch::UsageError(option + ": '" + text + "' in '" + whole +
                            "' is not an id (expected non-negative ids and ranges, e.g. 1,2,5-7)");
  }
  return std::stoi(text);
}

// A CLI11 validator running `check`, so bad values are reported while parsing (exit 2).
template <class Check>
CLI::Validator validator(const std::string& name, Check check) {
  return CLI::Validator(
      [check](std::string& value) -> std::string {
        try {
          check(value);
        } catch (const batch::UsageError& error) {
          return error.what();
        }
        return "";
      },
      "", name);
}

}  // namespace

std::vector<int> parse_id_list(const std::string& text, const std::string& option) {
  std::vector<int> ids;
  if (text.empty()) return ids;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string token = text.substr(start, comma - start);
    const std::size_t dash = token.find('-');
    if (dash == std::string::npos) {
      ids.push_back(parse_id(token, option, text));
    } else {
      const int first = parse_id(token.substr(0, dash), option, text);
      const int last = parse_id(token.substr(dash + 1), option, text);
      if (last < first || static_cast<long>(last) - first > kMaxRangeSpan) {
        throw batch::UsageError(option + ": range '" + token +
                                "' must be FIRST-LAST with FIRST <= LAST" + " and at most " +
                                std::to_string(kMaxRangeSpan) + " ids");
      }
      for (int id = first; id <= last; ++id) ids.push_back(id);
    }
    start = comma + 1;
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

void add_dataset_options(CLI::App& command, DatasetOptions* options) {
  options->jobs = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  command.add_option("DATASET", options->dataset, "BOP dataset folder (holds models/ and splits)")
      ->type_name("")
      ->required()
      ->check(CLI::Validator(CLI::ExistingDirectory).description(""));
  command.add_option("--split", options->split, "split folder to process (test, train_pbr, ...)")
      ->type_name("NAME")
      ->capture_default_str();
  command
      .add_option("--scenes", options->scenes,
                  "scene ids to process, e.g. 1,2,5-7 (default: all scenes of the split)")
      ->type_name("IDS")
      ->check(validator("", [](const std::string& v) { parse_id_list(v, "--scenes"); }));
  command
      .add_option("--images", options->images,
                  "image ids to process within each scene, e.g. 0-99 (default: all)")
      ->type_name("IDS")
      ->check(validator("", [](const std::string& v) { parse_id_list(v, "--images"); }));
  command
      .add_option("--out", options->out,
                  "output folder; re-running into it resumes, a different job is refused")
      ->type_name("DIR")
      ->required();
  command
      .add_option("--jobs,-j", options->jobs,
                  "worker threads, one render context and one core each (on llvmpipe "
                  "unless LP_NUM_THREADS is set)")
      ->type_name("N")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024).description(""));
  command
      .add_option("--shard", options->shard,
                  "process only shard I of N (image k of the sorted list goes to shard k mod N); "
                  "combine shard folders with `clutterscope merge`")
      ->type_name("I/N")
      ->check(validator("", [](const std::string& v) { batch::parse_shard(v); }));
  command
      .add_option("--split-type", options->split_type,
                  "BOP split type: reads folder SPLIT_TYPE (e.g. test_primesense) and the root "
                  "camera_TYPE.json where it exists")
      ->type_name("TYPE");
  command
      .add_option("--models-dir", options->models_dir,
                  "models folder under DATASET (e.g. models_eval, models_cad)")
      ->type_name("NAME")
      ->capture_default_str();
  command
      .add_option("--targets", options->targets,
                  "BOP test targets (test_targets_bop19.json: only the listed images and, per "
                  "image, the instances of the listed obj_ids; test_targets_bop24.json: only "
                  "the listed images)")
      ->type_name("FILE");
  command.add_flag("--keep-going", options->keep_going,
                   "record images with bad data in summary.json and continue (exit code 1)");
  command.add_flag("--quiet,-q", options->quiet, "no progress output");
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

batch::BatchOptions batch_options_of(const DatasetOptions& options, const std::string& label) {
  warn_if_more_jobs_than_cores(options.jobs);
  batch::BatchOptions batch;
  batch.out_dir = options.out;
  batch.jobs = options.jobs;
  if (!options.shard.empty()) batch.shard = batch::parse_shard(options.shard);
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
  if (!open.IsValid(&why)) throw batch::UsageError("--models-dir/--split-type: " + why);
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

void InputCheckTotals::add(const nlohmann::json& image_checks) {
  rotations_off_orthonormal_ += image_checks.at("rotations_off").get<std::int64_t>();
  max_rotation_error_ =
      std::max(max_rotation_error_, image_checks.at("max_rotation_error").get<double>());
}

nlohmann::json InputCheckTotals::to_json() const {
  return {{"rotations_off_orthonormal_1e-6", rotations_off_orthonormal_},
          {"max_rotation_orthonormality_error", max_rotation_error_},
          {"note",
           "GT rotations (cam_R_m2c) are used as stored, as bop_toolkit does; accepted up to "
           "|R^T R - I| = 0.02, refused beyond"}};
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

}  // namespace clutterscope::cli
