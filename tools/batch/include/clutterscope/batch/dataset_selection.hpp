#pragma once

// The dataset selection every per-image batch job shares (DATASET, --split, --split-type,
// --models-dir, --targets, --scenes, --images, --out, --jobs, --shard, --keep-going, --quiet),
// without its command-line registration (cli/dataset_options.hpp): the jobs take it in their
// Options, and the fingerprint entries and the item list follow from it.

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/depth_check.hpp>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace clutterscope::batch {

struct DatasetOptions {
  std::string dataset;  // DATASET positional: a BOP dataset folder
  std::string split = "test";
  std::string scenes;  // "1,2,5-7"; empty = all
  std::string images;  // same syntax; empty = all
  std::string out;     // --out DIR
  int jobs = 0;        // 0 until parsed: the default is the number of cores
  std::string shard;   // "i/n"; empty = whole job
  bool keep_going = false;
  bool quiet = false;
  std::string models_dir = "models";  // --models-dir NAME (models_eval, models_cad, ...)
  std::string split_type;             // --split-type TYPE: folder SPLIT_TYPE, camera_TYPE.json
  std::string targets;                // --targets FILE: test_targets_bop19/bop24.json
};

// Parses "1,2,5-7" into sorted unique ids, ranges expanded (the canonical form of a selection,
// for fingerprints). Throws UsageError naming `option` when malformed.
std::vector<int> parse_id_list(const std::string& text, const std::string& option);

// The canonical text of sorted unique ids: {1, 2, 5, 6, 7} -> "1,2,5-7" ("" = all).
std::string format_id_list(const std::vector<int>& ids);

// An id selection as given: ids one by one (each must exist) and ranges FIRST-LAST (each
// selects the ids that exist within it, so "0-99" works on the sparse image ids of BOP
// datasets, and must select at least one). Empty: every id.
struct IdSelection {
  std::vector<int> ids;
  std::vector<std::pair<int, int>> ranges;  // first, last (both included)
  bool selects_all() const { return ids.empty() && ranges.empty(); }
};

// Parses "1,2,5-7". Throws UsageError naming `option` when malformed.
IdSelection parse_id_selection(const std::string& text, const std::string& option);

// The ids of `selection` among `existing` (sorted unique), sorted. Throws datasets::DatasetError
// against `file` naming an id that does not exist, or a range that selects none (with the ids
// there are, briefly); `what` names the kind, e.g. "scene".
std::vector<int> select_ids(const IdSelection& selection, const std::vector<int>& existing,
                            const std::string& what, const std::filesystem::path& file);

// The images of the options' selection (scenes, images, split, targets) in job order: what
// selection_of lists, with ranges selecting the ids that exist. Throws datasets::DatasetError
// as select_ids does and as BopDataset::list_images does.
std::vector<datasets::ImageKey> list_selected_images(const datasets::BopDataset& dataset,
                                                     const DatasetOptions& options);

// The split folder of the options: SPLIT, or SPLIT_TYPE with --split-type.
std::string split_folder(const DatasetOptions& options);

// The dataset selection (one split folder, scene and image ids, ranges expanded) of the
// options; list_selected_images resolves ranges to the ids that exist.
datasets::DatasetSelection selection_of(const DatasetOptions& options);

// Opens the dataset with --models-dir and --split-type, and attaches --targets when given.
// Throws DatasetError for a bad dataset or targets file, UsageError for a bad folder name.
datasets::BopDataset open_dataset(const DatasetOptions& options);

// Input checks of one image, for its persisted per-image summary: how many GT rotations are
// further than kRotationReportThreshold from orthonormal, and the largest error.
nlohmann::json input_checks_of(const datasets::SceneView& view);

// The entry a job adds to an image's input_checks when its measured depth image has no value
// > 0 (a camera that gave no depth, a placeholder file): {"split", "scene_id", "im_id",
// "depth_file"} under kNoDepthValuesKey, the file relative to the dataset root when inside it.
inline constexpr const char* kNoDepthValuesKey = "depth_without_values";
nlohmann::json no_depth_values_entry(const datasets::ImageKey& key,
                                     const std::filesystem::path& depth_file,
                                     const std::filesystem::path& dataset_root);

// The warning line (no newline) for such an entry: "warning: FILE: scene S, image I: the depth
// image has no value > 0 (no depth at all); " + consequence.
std::string no_depth_values_warning(const nlohmann::json& entry, const std::string& consequence);

// Sums input_checks_of over the images of a batch, for summary.json, byte-stable across
// --jobs, resume and merge: the sums do not depend on the order, the list is in item order
// (the order the batch streams the items in). With `depth_values_checked` (jobs that read the
// measured depth), also the images without depth values: their count and the first
// kListedImages of them.
class InputCheckTotals {
 public:
  static constexpr std::size_t kListedImages = 100;
  explicit InputCheckTotals(bool depth_values_checked = false)
      : depth_values_checked_(depth_values_checked) {}
  void add(const nlohmann::json& image_checks);
  nlohmann::json to_json() const;

 private:
  std::int64_t rotations_off_orthonormal_ = 0;
  double max_rotation_error_ = 0.0;
  bool depth_values_checked_ = false;
  std::int64_t images_without_depth_values_ = 0;
  nlohmann::json listed_without_depth_values_ = nlohmann::json::array();
};

// One line on stderr, once per process, when `jobs` exceeds the machine's cores (the run goes
// on: threads beyond the cores only compete for them).
void warn_if_more_jobs_than_cores(int jobs);

// Batch options (out, jobs, shard, keep-going, quiet) of the options; warns as
// warn_if_more_jobs_than_cores does.
batch::BatchOptions batch_options_of(const DatasetOptions& options, const std::string& label);

// The fingerprint entries every dataset command shares: absolute dataset path, split, and the
// canonical scene and image id lists (format_id_list); split_type, models_dir and the absolute
// targets path only where given (so fingerprints of runs without them are unchanged). Commands add
// their own result-changing options to it.
nlohmann::json dataset_fingerprint(const DatasetOptions& options);

// Adds what changes results to a job fingerprint: "depth_scale" when given, "depth_check":
// false with --no-depth-check (the defaults add nothing, so earlier folders keep resuming).
void add_depth_check_fingerprint(const datasets::DepthCheckOptions& options,
                                 nlohmann::json* fingerprint);

}  // namespace clutterscope::batch
