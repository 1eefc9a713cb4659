#include <algorithm>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <fstream>
#include <nlohmann/json.hpp>
#include <vector>

namespace clutterscope::batch {

namespace fs = std::filesystem;

namespace {

// Commands whose results folder is marked by DIR/.COMMAND/job.json.
constexpr const char* kMarkedCommands[] = {"report", "simulate", "render"};

std::vector<fs::path>& delegated_roots() {
  static std::vector<fs::path> roots;
  return roots;
}

fs::path normalized(const fs::path& dir) {
  std::error_code error;
  fs::path path = fs::weakly_canonical(fs::absolute(dir), error);
  if (error) path = fs::absolute(dir).lexically_normal();
  if (path.filename().empty() && path.has_parent_path() && path != path.root_path()) {
    path = path.parent_path();  // "out/" -> "out"
  }
  return path;
}

bool is_delegated(const fs::path& dir) {
  const auto& roots = delegated_roots();
  return std::find(roots.begin(), roots.end(), dir) != roots.end();
}

// The command recorded in a batch job file; a damaged file still marks a batch folder.
std::string batch_command(const fs::path& job) {
  try {
    std::ifstream file(job, std::ios::binary);
    return nlohmann::json::parse(file).at("fingerprint").at("command").get<std::string>();
  } catch (const std::exception&) {
    return "a batch command";
  }
}

// A marker folder left without its job.json by an interrupted setup is not a user's file.
bool is_marker_folder(const std::string& name) {
  if (name == ".batch") return true;
  for (const char* command : kMarkedCommands) {
    if (name == std::string(".") + command) return true;
  }
  return false;
}

std::string describe(const FolderOwner& owner) {
  return "the results of `" + owner.command + "` (" + owner.marker.string() + ")";
}

// Refuses when a folder above `path` holds another command's results (datasets may hold
// results folders; a delegated root's own steps may write inside it).
void check_folders_above(const fs::path& path, const fs::path& as_given) {
  for (fs::path above = path.parent_path(); !above.empty(); above = above.parent_path()) {
    const std::optional<FolderOwner> owner = folder_owner(above);
    if (owner && owner->command != "dataset" && !is_delegated(above)) {
      throw UsageError(as_given.string() + " is inside " + above.string() + ", which holds " +
                       describe(*owner) + "; its folders belong to it: choose another --out");
    }
    if (above == above.root_path()) break;
  }
}

// BOP scene folders are named by six digits (000000, 000048, ...).
bool is_scene_folder_name(const std::string& name) {
  return name.size() == 6 &&
         std::all_of(name.begin(), name.end(), [](char c) { return c >= '0' && c <= '9'; });
}

bool holds_scene_files(const fs::path& dir) {
  std::error_code error;
  return fs::is_regular_file(dir / "scene_gt.json", error) ||
         fs::is_regular_file(dir / "scene_camera.json", error);
}

// What `dir` is in a BOP dataset, with the file that shows it; nullopt for anything else
// (a dataset's root, a results folder, an unrelated folder).
std::optional<std::pair<std::string, fs::path>> dataset_content(const fs::path& dir) {
  std::error_code error;
  if (!fs::is_directory(dir, error)) return std::nullopt;
  if (holds_scene_files(dir)) {
    const fs::path shown = fs::exists(dir / "scene_gt.json", error) ? dir / "scene_gt.json"
                                                                    : dir / "scene_camera.json";
    return std::pair{std::string("scene folder"), shown};
  }
  if (fs::is_regular_file(dir / "models_info.json", error)) {
    return std::pair{std::string("models folder"), dir / "models_info.json"};
  }
  // A split folder (test, train_pbr, val, ...) holds scene folders; the first one is named.
  std::optional<fs::path> first;
  for (const auto& entry : fs::directory_iterator(dir, error)) {
    if (is_scene_folder_name(entry.path().filename().string()) && holds_scene_files(entry.path()) &&
        (!first || entry.path() < *first)) {
      first = entry.path();
    }
  }
  if (first) return std::pair{std::string("split folder"), *first};
  return std::nullopt;
}

}  // namespace

void refuse_dataset_content(const fs::path& path, const std::string& what) {
  const fs::path target = normalized(path);
  for (fs::path dir = target; !dir.empty(); dir = dir.parent_path()) {
    if (const auto content = dataset_content(dir)) {
      const std::string where =
          dir == target ? " is a dataset's " : " is inside " + dir.string() + ", a dataset's ";
      throw UsageError(what + " " + path.string() + where + content->first + " (it holds " +
                       content->second.string() +
                       "): a dataset's split, scene and models folders are not written to, so "
                       "that the dataset stays readable; choose another " +
                       what);
    }
    if (dir == dir.root_path()) break;
  }
}

std::optional<FolderOwner> folder_owner(const fs::path& dir) {
  std::error_code error;
  const fs::path batch = dir / ".batch" / "job.json";
  if (fs::is_regular_file(batch, error)) return FolderOwner{batch_command(batch), batch};
  for (const char* command : kMarkedCommands) {
    const fs::path marker = dir / (std::string(".") + command) / "job.json";
    if (fs::is_regular_file(marker, error)) return FolderOwner{command, marker};
  }
  const fs::path dataset = dir / "models" / "models_info.json";
  if (fs::is_regular_file(dataset, error)) return FolderOwner{"dataset", dataset};
  return std::nullopt;
}

void claim_output_folder(const fs::path& dir, const std::string& command) {
  const fs::path path = normalized(dir);
  refuse_dataset_content(dir, "--out");
  check_folders_above(path, dir);
  std::error_code error;
  if (!fs::exists(path, error)) return;
  if (!fs::is_directory(path, error)) {
    throw UsageError(dir.string() + " exists and is not a folder; choose another --out");
  }
  if (const std::optional<FolderOwner> owner = folder_owner(path)) {
    if (owner->command == command) return;
    if (owner->command == "dataset") {
      throw UsageError(dir.string() + " is a dataset (" + owner->marker.string() +
                       "): results are not written into a dataset; choose another --out");
    }
    throw UsageError(dir.string() + " holds " + describe(*owner) + "; choose another --out");
  }
  std::vector<std::string> entries;
  for (const auto& entry : fs::directory_iterator(path, error)) {
    const std::string name = entry.path().filename().string();
    if (!is_marker_folder(name)) entries.push_back(name);
  }
  if (!entries.empty()) {
    const std::string first = *std::min_element(entries.begin(), entries.end());
    throw UsageError(dir.string() + " is not empty and is not a clutterscope " + command +
                     " folder (it holds " + (dir / first).string() +
                     ", which could be overwritten): choose a new or empty --out");
  }
}

void claim_output_file(const fs::path& file, const std::string& option, const std::string& command,
                       const std::function<bool(const fs::path&)>& written_by_command) {
  const fs::path path = normalized(file);
  std::error_code error;
  if (fs::is_directory(path, error)) {
    throw UsageError(file.string() + " is a folder; " + option + " names the output file");
  }
  if (file.filename().empty()) {  // "DIR/": a folder that does not exist yet
    throw UsageError(option + " " + file.string() + " ends with '/', which names a folder; " +
                     option + " names the output file (e.g. " +
                     (file / (command + ".json")).string() + ")");
  }
  refuse_dataset_content(file, option);
  check_folders_above(path, file);
  if (fs::exists(path, error) && !written_by_command(path)) {
    throw UsageError(option + " " + file.string() + " exists and is not a file `" + command +
                     "` wrote; it is not replaced: choose another " + option +
                     ", or remove the file yourself");
  }
}

void mark_output_folder(const fs::path& dir, const std::string& command) {
  const nlohmann::ordered_json marker = {{"command", command},
                                         {"tool_version", CLUTTERSCOPE_VERSION}};
  datasets::write_file_atomically(dir / ("." + command) / "job.json", marker.dump(2) + "\n");
}

DelegatedOutput::DelegatedOutput(const fs::path& root) {
  delegated_roots().push_back(normalized(root));
}

DelegatedOutput::~DelegatedOutput() { delegated_roots().pop_back(); }

}  // namespace clutterscope::batch
