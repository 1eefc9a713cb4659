// The files of a report folder: writing them, and reading objects.csv back for
// `clutterscope thresholds`.

#include <algorithm>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/report/report.hpp>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

namespace clutterscope::report {

namespace {

bool valid_plot_name(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char ch) {
    return (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_' || ch == '-';
  });
}

// The dataset path recorded by the marker of `dir` (a report's or a batch job's), if any.
std::optional<std::string> recorded_dataset(const std::filesystem::path& dir) {
  for (const auto& [marker, pointer] :
       {std::pair<const char*, const char*>{".report/job.json", "/dataset/dataset"},
        {".batch/job.json", "/fingerprint/dataset"}}) {
    std::ifstream in(dir / marker);
    if (!in) continue;
    const nlohmann::json json = nlohmann::json::parse(in, nullptr, false);
    const nlohmann::json::json_pointer at(pointer);
    if (json.is_object() && json.contains(at) && json.at(at).is_string()) {
      return json.at(at).get<std::string>();
    }
  }
  return std::nullopt;
}

bool report_may_write(const std::filesystem::path& dir) {
  try {
    batch::claim_output_folder(dir, "report");
    return true;
  } catch (const batch::UsageError&) {
    return false;
  }
}

// The folder `clutterscope report` should write for `dir` (see report_advice).
std::filesystem::path advised_report_folder(const std::filesystem::path& dir) {
  const std::filesystem::path absolute = std::filesystem::absolute(dir).lexically_normal();
  for (std::filesystem::path above = absolute; !above.empty(); above = above.parent_path()) {
    const std::optional<batch::FolderOwner> owner = batch::folder_owner(above);
    if (owner && owner->command == "report") return above == absolute ? dir : above;
    if (above == above.root_path()) break;
  }
  if (report_may_write(dir)) return dir;
  std::filesystem::path base = dir;
  if (base.filename().empty()) base = base.parent_path();  // "out/"
  for (int suffix = 1; suffix <= 20; ++suffix) {
    std::filesystem::path sibling = base;
    sibling += suffix == 1 ? "_report" : "_report" + std::to_string(suffix);
    if (report_may_write(sibling)) return sibling;
  }
  return "NEW_DIR";  // inside another command's results: no sibling will do
}

}  // namespace

std::string report_advice(const std::filesystem::path& dir, const std::string& command) {
  const std::filesystem::path out = advised_report_folder(dir);
  const std::optional<batch::FolderOwner> owner = batch::folder_owner(out);
  const bool is_report = owner && owner->command == "report";
  if (is_report && out != dir &&
      std::filesystem::exists(out / batch::report_objects_table().file_name)) {
    return "this folder belongs to the report in " + out.string() + ": run `clutterscope " +
           command + "` on " + out.string();
  }
  std::optional<std::string> dataset = recorded_dataset(out);
  if (!dataset) dataset = recorded_dataset(dir);
  return "run `clutterscope report " + dataset.value_or("DATASET") + " --out " + out.string() +
         "`" + (is_report ? " (with the options the report was started with)" : "") +
         " first, then `clutterscope " + command + "` on " + out.string();
}

ReportFiles write_report(const std::filesystem::path& dir, const std::vector<ObjectRow>& objects,
                         const ReportAnalysis& analysis, const std::vector<NamedPlot>& plots,
                         const nlohmann::ordered_json& run, const EvaluationResults* evaluation) {
  for (const NamedPlot& plot : plots) {
    if (!valid_plot_name(plot.name)) {
      throw std::invalid_argument("plot name \"" + plot.name + "\" must match [a-z0-9_-]+");
    }
  }
  ReportFiles files;
  std::filesystem::create_directories(dir / "plots");
  files.objects_csv = dir / batch::report_objects_table().file_name;
  files.images_csv = dir / batch::report_images_table().file_name;
  files.summary_json = dir / "summary.json";
  files.report_html = dir / "report.html";
  datasets::write_file_atomically(files.objects_csv, format_objects_csv(objects));
  datasets::write_file_atomically(files.images_csv, format_images_csv(analysis.images));
  datasets::write_file_atomically(files.summary_json,
                                  summary_json(analysis, run, evaluation).dump(2) + "\n");
  for (const NamedPlot& plot : plots) {
    files.plots.push_back(dir / "plots" / (plot.name + ".svg"));
    datasets::write_file_atomically(files.plots.back(),
                                    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" + plot.svg);
  }
  datasets::write_file_atomically(files.report_html, report_html(analysis, plots, run, evaluation));
  return files;
}

std::vector<ObjectRow> load_report_objects(const std::filesystem::path& dir) {
  const std::filesystem::path path = dir / batch::report_objects_table().file_name;
  if (!std::filesystem::exists(path)) {
    throw datasets::DatasetError(
        path, "no objects.csv in this folder: " + report_advice(dir, "thresholds"));
  }
  if (!objects_csv_has_estimates(path)) {
    throw datasets::DatasetError(path, "objects.csv has visibility columns only, no estimates: " +
                                           report_advice(dir, "thresholds"));
  }
  std::vector<ObjectRow> objects = read_objects_csv(path);
  const bool any_estimate = std::any_of(objects.begin(), objects.end(),
                                        [](const ObjectRow& row) { return row.estimate; });
  if (!any_estimate) {
    throw datasets::DatasetError(
        path, "no object in objects.csv has an estimate: " + report_advice(dir, "thresholds"));
  }
  return objects;
}

bool ThresholdCheckOptions::IsValid(std::string* why) const {
  ThresholdOptions thresholds;
  thresholds.chosen_threshold_cm2 = variance_cm2;
  thresholds.visibility_cutoff = visibility_cutoff;
  thresholds.chosen_radius_cm = radius_cm;
  if (accurate_cm) thresholds.accurate_cm = *accurate_cm;
  if (!thresholds.IsValid(why)) {
    // Name this command's options, not the report's.
    for (const auto& [report_name, name] :
         {std::pair<std::string, std::string>{"--variance-threshold-cm2", "--variance-cm2"},
          {"--confidence-radius-cm", "--radius-cm"}}) {
      const size_t at = why->find(report_name);
      if (at != std::string::npos) why->replace(at, report_name.size(), name);
    }
    return false;
  }
  return true;
}

std::string threshold_check(const ThresholdCheckOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  // Over the objects in view, as the report computed its thresholds.
  const std::vector<ObjectRow> objects = objects_in_view(load_report_objects(options.report_dir));
  double accurate_cm = 1.0;
  const std::filesystem::path summary = options.report_dir / "summary.json";
  if (options.accurate_cm) {
    accurate_cm = *options.accurate_cm;
  } else if (std::filesystem::exists(summary)) {
    std::ifstream in(summary);
    const nlohmann::json json = nlohmann::json::parse(in, nullptr, false);
    const auto* value = json.is_object() && json.contains("options") && json["options"].is_object()
                            ? &json["options"]
                            : nullptr;
    if (!value || !value->contains("accurate_cm") || !(*value)["accurate_cm"].is_number() ||
        !((*value)["accurate_cm"].get<double>() > 0.0)) {
      throw datasets::DatasetError(summary,
                                   "options.accurate_cm: missing or not a positive "
                                   "number (pass --accurate-cm)");
    }
    accurate_cm = (*value)["accurate_cm"].get<double>();
  }
  return format_threshold_check(objects, options.variance_cm2, options.visibility_cutoff,
                                accurate_cm, options.radius_cm);
}

}  // namespace clutterscope::report
