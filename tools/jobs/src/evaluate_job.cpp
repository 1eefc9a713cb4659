#include <algorithm>
#include <chrono>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/input_digest.hpp>
#include <clutterscope/batch/run_record.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/bop_gt_info.hpp>
#include <clutterscope/datasets/bop_image_files.hpp>
#include <clutterscope/datasets/bop_pose_models.hpp>
#include <clutterscope/datasets/bop_results.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/estimator/bop_pose_errors.hpp>
#include <clutterscope/estimator/bop_scores.hpp>
#include <clutterscope/jobs/evaluate_job.hpp>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer_in_use.hpp>
#include <clutterscope/report/by_visibility.hpp>
#include <clutterscope/report/tables.hpp>
#include <clutterscope/scene_estimation/bop_vsd.hpp>
#include <clutterscope/visibility/bop_visibility.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace clutterscope::jobs {

using namespace scene_estimation;  // the library this job runs (moved here, issue 26)

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

// BOP 2019: per target object its inst_count most visible GT instances count
// (eval_bop19_pose.py's visib_gt_min = -1).
constexpr double kBop19VisibGtMin = -1.0;

// The estimates of one results file by image, then object, each list in file order (the order
// bop_toolkit's est_id counts in).
using ImageEstimates = std::map<int, std::vector<const datasets::PoseEstimate*>>;
using FileEstimates = std::map<std::pair<int, int>, ImageEstimates>;

struct ResultsFile {
  std::string name;  // the file name without .csv: the key of every output
  fs::path path;
  std::vector<datasets::PoseEstimate> estimates;
  FileEstimates by_image;
};

// What the errors of one model need: every vertex (metres), its symmetry transformations.
struct ModelData {
  estimator::ModelPoints points;
  std::vector<Eigen::Isometry3d> symmetries;
  double diameter_m = 0;
};

bool has(const std::vector<std::string>& errors, const char* name) {
  return std::find(errors.begin(), errors.end(), name) != errors.end();
}

using report::PoseMetric;
constexpr PoseMetric kMetrics[] = {PoseMetric::kVsd, PoseMetric::kMssd, PoseMetric::kMspd};

// The computed metrics of a fingerprint's "errors", in PoseMetric order (scores.json's and
// bop19_average_recall's order).
std::vector<PoseMetric> metrics_of(const Json& errors) {
  std::vector<PoseMetric> metrics;
  for (const PoseMetric metric : kMetrics) {
    if (std::find(errors.begin(), errors.end(), report::to_string(metric)) != errors.end()) {
      metrics.push_back(metric);
    }
  }
  return metrics;
}

// BOP 2019's thresholds of a metric as the scores use them (estimator/bop_scores.hpp).
std::vector<double> score_thresholds(PoseMetric metric) {
  return metric == PoseMetric::kMspd ? estimator::bop19_mspd_thresholds_px()
                                     : estimator::bop19_fraction_thresholds();
}

// VSD's misalignment tolerances; one placeholder for MSSD and MSPD, which have none.
std::vector<double> taus_of(PoseMetric metric) {
  return metric == PoseMetric::kVsd ? estimator::bop19_fraction_thresholds()
                                    : std::vector<double>{std::nan("")};
}

// Where BOP puts an image's depth image, for naming it when it is missing.
fs::path expected_depth_path(const fs::path& root, const datasets::ImageKey& key) {
  return root / key.split / datasets::six_digits(key.scene_id) / "depth" /
         (datasets::six_digits(key.im_id) + ".png");
}

// A pose in the model file's millimetres, as bop_toolkit renders (the readers give metres).
BopPose pose_mm(const Eigen::Isometry3d& model_to_camera) {
  return {model_to_camera.linear(), model_to_camera.translation() * 1000.0};
}

// A normalised error for the per-item summary: JSON has no infinity, so a non-finite error
// (MSSD's shortcut, an MSPD through depth 0) is null, which never matches, as inf and NaN never
// match in bop_toolkit.
Json error_json(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }
double error_of(const Json& value) { return value.is_null() ? HUGE_VAL : value.get<double>(); }

fs::path scene_gt_info_path(const datasets::BopDataset& dataset, const std::string& split,
                            int scene_id) {
  return dataset.root() / split / datasets::six_digits(scene_id) / "scene_gt_info.json";
}

// The scene's scene_gt_info.json, which must exist: its visib_fract decides the GT that counts.
void require_scene_gt_info(const datasets::BopDataset& dataset, const std::string& split,
                           int scene_id) {
  const fs::path path = scene_gt_info_path(dataset, split, scene_id);
  std::error_code error;
  if (!fs::is_regular_file(path, error)) {
    throw datasets::DatasetError(
        path,
        "missing: the evaluation needs the bop19 visib_fract of every GT instance, which "
        "decides the GT instances that count (bop_toolkit's calc_gt_info.py writes it; so "
        "does `clutterscope visibility --mode bop19 --write-bop-info`)");
  }
}

// Adds the seconds since `start` to *seconds and returns now.
using StageClock = std::chrono::steady_clock;
StageClock::time_point add_elapsed(StageClock::time_point start, double* seconds) {
  const StageClock::time_point now = StageClock::now();
  *seconds += std::chrono::duration<double>(now - start).count();
  return now;
}

// Guards the EvaluateStageTimes the workers add theirs to.
std::mutex stage_times_mutex;

class EvaluateWorker {
 public:
  // vsd: VSD's options when VSD is computed; the worker then renders on its own context.
  EvaluateWorker(const datasets::BopDataset& dataset, const EvaluateJobOptions& job,
                 const std::vector<ResultsFile>& files, const datasets::TestTargets& targets,
                 const std::map<int, datasets::ModelSymmetries>& symmetries,
                 const std::optional<BopVsdOptions>& vsd)
      : dataset_(dataset),
        files_(files),
        targets_(targets),
        symmetries_(symmetries),
        mssd_(has(job.errors, "mssd")),
        mspd_(has(job.errors, "mspd")),
        vsd_options_(vsd),
        stage_times_(job.stage_times) {
    if (vsd_options_) {
      context_.emplace(render::EglContext::create());
      // VSD's own renderer (bop_vsd.hpp): it draws on an image-sized target.
      renderer_.emplace(*context_);
    }
  }

  ~EvaluateWorker() {
    if (stage_times_ == nullptr) return;
    const std::lock_guard<std::mutex> lock(stage_times_mutex);
    stage_times_->add(times_);
  }
  EvaluateWorker(const EvaluateWorker&) = delete;
  EvaluateWorker& operator=(const EvaluateWorker&) = delete;

  batch::ItemOutput run(const datasets::ImageKey& key) {
    const StageClock::time_point start = StageClock::now();
    ++times_.images;
    const datasets::SceneView view = dataset_.load(key);
    const std::vector<double>& visib_fract = visib_fract_of(key, view);
    const std::map<int, int>& targets = targets_.images.at({key.scene_id, key.im_id});
    std::vector<estimator::BopGtInstance> gt;
    for (std::size_t k = 0; k < view.objects.size(); ++k) {
      gt.push_back({view.objects[k].obj_id, visib_fract[k]});
    }
    const std::vector<bool> valid = estimator::bop_valid_gt(gt, targets, kBop19VisibGtMin);

    // One VSD image for every results file: the GT renders are shared.
    cv::Mat depth_mm;
    std::optional<BopVsdImage> vsd_image;
    if (vsd_options_) {
      const std::string where = datasets::location(key.scene_id, key.im_id);
      if (view.depth_path.empty()) {
        throw datasets::DatasetError(expected_depth_path(dataset_.root(), key),
                                     where + "missing: VSD needs the measured depth image");
      }
      depth_mm = visibility::load_bop_depth_mm(view.depth_path.string(), view.camera.depth_scale,
                                               view.camera.width, view.camera.height, where);
      vsd_image.emplace(*renderer_, depth_mm, view.camera.K, *vsd_options_);
    }
    add_elapsed(start, &times_.load_s);

    Json gt_json = Json::array(), targets_json = Json::array(), files_json = Json::array();
    for (const auto& instance : gt) gt_json.push_back({instance.obj_id, instance.visib_fract});
    for (const auto& [obj_id, inst_count] : targets) targets_json.push_back({obj_id, inst_count});
    std::string rows;
    for (const ResultsFile& file : files_) {
      files_json.push_back(evaluate_file(file, key, view, gt, valid, targets,
                                         vsd_image ? &*vsd_image : nullptr, &rows));
    }
    if (vsd_image) {
      times_.vsd_renders += vsd_image->renders();
      times_.vsd_skipped_pairs += vsd_image->skipped_pairs();
    }
    batch::ItemOutput output;
    output.tables = {rows};
    output.summary = {{"gt", gt_json}, {"targets", targets_json}, {"files", files_json}};
    return output;
  }

 private:
  // The evaluated estimates of one results file in this image: errors.csv rows, and for the
  // scores {"estimates_in_image", "evaluated": [{obj_id, est_id, score, gt_ids, mssd, mspd,
  // vsd}]} with the errors normalised as their thresholds are (vsd: per GT its value per tau).
  Json evaluate_file(const ResultsFile& file, const datasets::ImageKey& key,
                     const datasets::SceneView& view,
                     const std::vector<estimator::BopGtInstance>& gt,
                     const std::vector<bool>& valid, const std::map<int, int>& targets,
                     BopVsdImage* vsd_image, std::string* rows) {
    Json evaluated = Json::array();
    std::size_t in_image = 0;
    const auto image = file.by_image.find({key.scene_id, key.im_id});
    if (image != file.by_image.end()) {
      for (const auto& entry : image->second) in_image += entry.second.size();
    }
    // MSPD thresholds are for 640 px wide images (eval_calc_scores.py).
    const double width_factor = 640.0 / view.camera.width;
    // errors.csv's vsd_tau columns: BOP 2019's taus.
    const std::size_t vsd_columns = estimator::bop19_fraction_thresholds().size();
    for (const auto& [obj_id, inst_count] : targets) {
      if (image == file.by_image.end()) break;
      const auto found = image->second.find(obj_id);
      if (found == image->second.end()) continue;  // a missed target
      const std::vector<const datasets::PoseEstimate*>& estimates = found->second;
      std::vector<double> scores;
      for (const auto* estimate : estimates) scores.push_back(estimate->score);
      const ModelData& model = model_data(obj_id);
      for (const int est_id : estimator::bop_top_estimates(scores, inst_count)) {
        const datasets::PoseEstimate& estimate = *estimates[est_id];
        ++times_.estimates;
        Json gt_ids = Json::array(), mssd = Json::array(), mspd = Json::array();
        Json vsd_values = Json::array();
        for (std::size_t k = 0; k < view.objects.size(); ++k) {
          if (view.objects[k].obj_id != obj_id) continue;
          const Eigen::Isometry3d& pose = view.objects[k].model_to_camera;
          double mssd_m = HUGE_VAL, mspd_px = HUGE_VAL;
          std::vector<double> vsd;
          batch::CsvRow row;
          row.add(file.name).add(key.scene_id).add(key.im_id).add(obj_id).add(est_id);
          row.add(static_cast<int>(k)).add(batch::format_shortest(estimate.score));
          row.add(batch::format_shortest(gt[k].visib_fract)).add(valid[k] ? "1" : "0");
          ++times_.pairs;
          StageClock::time_point start = StageClock::now();
          if (mssd_) {
            mssd_m = estimator::bop_mssd(estimate.model_to_camera, pose, model.points,
                                         model.symmetries, model.diameter_m);
            mssd.push_back(error_json(mssd_m / model.diameter_m));
            start = add_elapsed(start, &times_.mssd_s);
          }
          if (mspd_) {
            mspd_px = estimator::mspd(estimate.model_to_camera, pose, view.camera.K, model.points,
                                      model.symmetries);
            mspd.push_back(error_json(mspd_px * width_factor));
            start = add_elapsed(start, &times_.mspd_s);
          }
          if (vsd_image != nullptr) {
            // VSD in the model file's millimetres, as bop_toolkit renders.
            vsd = vsd_image->vsd(gpu_model(obj_id), model.diameter_m * 1000.0,
                                 pose_mm(estimate.model_to_camera), pose_mm(pose));
            vsd_values.push_back(vsd);
            add_elapsed(start, &times_.vsd_s);
          }
          // Empty: not computed (not in --errors, or MSSD's centres a diameter or more apart,
          // which bop_toolkit records as inf) or not finite (an MSPD through depth 0).
          row.add(mssd_ ? batch::format_shortest(1e3 * mssd_m) : "");
          row.add(mspd_ ? batch::format_shortest(mspd_px) : "");
          for (std::size_t i = 0; i < vsd_columns; ++i) {
            row.add(i < vsd.size() ? batch::format_shortest(vsd[i]) : "");
          }
          *rows += row.str();
          gt_ids.push_back(k);
        }
        evaluated.push_back({{"obj_id", obj_id},
                             {"est_id", est_id},
                             {"score", estimate.score},
                             {"gt_ids", gt_ids},
                             {"mssd", mssd},
                             {"mspd", mspd},
                             {"vsd", vsd_values}});
      }
    }
    return {{"estimates_in_image", in_image}, {"evaluated", evaluated}};
  }

  // The model uploaded to this worker's context in its file's units (bop_toolkit renders mm).
  const render::BopModel& gpu_model(int obj_id) {
    const auto found = gpu_models_.find(obj_id);
    if (found != gpu_models_.end()) return *found->second;
    auto model = std::make_unique<render::BopModel>(
        render::BopModel::upload(datasets::load_mesh(dataset_.model(obj_id).mesh_path, {1.0})));
    return *gpu_models_.emplace(obj_id, std::move(model)).first->second;
  }

  // scene_gt_info.json's visib_fract of every GT instance (one scene kept per worker).
  const std::vector<double>& visib_fract_of(const datasets::ImageKey& key,
                                            const datasets::SceneView& view) {
    const fs::path path = scene_gt_info_path(dataset_, key.split, key.scene_id);
    if (scene_id_ != key.scene_id || scene_split_ != key.split) {
      require_scene_gt_info(dataset_, key.split, key.scene_id);
      scene_visib_ = datasets::read_scene_gt_visib_fract(path, key.scene_id);
      scene_id_ = key.scene_id;
      scene_split_ = key.split;
    }
    const auto found = scene_visib_.find(key.im_id);
    if (found == scene_visib_.end()) {
      throw datasets::DatasetError(
          path, datasets::location(key.scene_id, key.im_id) + "no entry for the image");
    }
    if (found->second.size() != view.objects.size()) {
      throw datasets::DatasetError(
          path, datasets::location(key.scene_id, key.im_id) + std::to_string(found->second.size()) +
                    " GT instances, scene_gt.json has " + std::to_string(view.objects.size()));
    }
    return found->second;
  }

  const ModelData& model_data(int obj_id) {
    const auto found = models_.find(obj_id);
    if (found != models_.end()) return found->second;
    const datasets::ModelInfo& info = dataset_.model(obj_id);
    ModelData data;
    data.points = datasets::load_model_vertices(info.mesh_path);
    std::vector<estimator::ContinuousSymmetry> continuous;
    const auto symmetries = symmetries_.find(obj_id);
    std::vector<Eigen::Isometry3d> discrete;
    if (symmetries != symmetries_.end()) {
      discrete = symmetries->second.discrete;
      for (const auto& symmetry : symmetries->second.continuous) {
        continuous.push_back({symmetry.axis, symmetry.offset});
      }
    }
    data.symmetries = estimator::symmetry_transformations(discrete, continuous);
    data.diameter_m = info.diameter;
    return models_.emplace(obj_id, std::move(data)).first->second;
  }

  const datasets::BopDataset& dataset_;
  const std::vector<ResultsFile>& files_;
  const datasets::TestTargets& targets_;
  const std::map<int, datasets::ModelSymmetries>& symmetries_;
  const bool mssd_, mspd_;
  const std::optional<BopVsdOptions> vsd_options_;
  EvaluateStageTimes* const stage_times_;
  EvaluateStageTimes times_;  // this worker's, added to *stage_times_ at its end
  std::map<int, ModelData> models_;
  // Destroyed before the context they live in (members go in reverse order).
  std::optional<render::EglContext> context_;
  std::optional<render::BopDepthRenderer> renderer_;
  std::map<int, std::unique_ptr<render::BopModel>> gpu_models_;
  int scene_id_ = -1;
  std::string scene_split_;
  std::map<int, std::vector<double>> scene_visib_;
};

// The recalls of one error type (one VSD tau) over `images`, in scores.json's layout, appended
// to `entries`: per threshold bop_toolkit's scores_th=*.json fields (obj_recalls: the recall of
// each target object; vsd_tau for VSD, tau NaN for the others).
void add_recall_entries(const std::vector<estimator::BopImageErrors>& images,
                        const std::vector<double>& thresholds, double tau,
                        std::map<int, std::vector<estimator::BopRecall>>* per_object,
                        std::vector<estimator::BopRecall>* overall, Json* entries) {
  std::set<int> objects;
  for (const auto& image : images) {
    for (const auto& entry : image.targets) objects.insert(entry.first);
  }
  // Per object: the images where it is a target, with only its targets and estimates.
  std::map<int, std::vector<estimator::BopImageErrors>> object_images;
  for (const int obj_id : objects) {
    for (const auto& image : images) {
      const auto target = image.targets.find(obj_id);
      if (target == image.targets.end()) continue;
      estimator::BopImageErrors only = image;
      only.targets = {*target};
      only.estimates.clear();
      const auto estimates = image.estimates.find(obj_id);
      if (estimates != image.estimates.end()) only.estimates.insert(*estimates);
      object_images[obj_id].push_back(std::move(only));
    }
  }
  for (const double threshold : thresholds) {
    const estimator::BopRecall recall = estimator::bop_recall(images, threshold, kBop19VisibGtMin);
    overall->push_back(recall);
    Json obj_recalls = Json::object();
    for (const auto& [obj_id, only] : object_images) {
      const estimator::BopRecall object = estimator::bop_recall(only, threshold, kBop19VisibGtMin);
      (*per_object)[obj_id].push_back(object);
      obj_recalls[std::to_string(obj_id)] = object.recall;
    }
    Json entry = {{"threshold", recall.threshold}, {"recall", recall.recall},
                  {"tp_count", recall.tp_count},   {"targets_count", recall.targets_count},
                  {"gt_count", recall.gt_count},   {"obj_recalls", obj_recalls}};
    if (!std::isnan(tau)) entry["vsd_tau"] = tau;
    entries->push_back(std::move(entry));
  }
}

// The by-visibility options `evaluate` sets, in the fingerprint (the summary builder of a
// resume or a merge reads them back from there).
Json by_visibility_fingerprint(const report::ByVisibilityOptions& options) {
  return {{"band_edges", options.band_edges},
          {"correct_metric", report::to_string(options.correct_metric)},
          {"correct_threshold", options.correct_threshold},
          {"min_precision", options.min_precision},
          {"seed", options.seed}};
}

report::ByVisibilityOptions by_visibility_options(const Json& fingerprint) {
  report::ByVisibilityOptions options;
  options.band_edges = fingerprint.at("band_edges").get<std::vector<double>>();
  options.correct_metric =
      *report::pose_metric_from_string(fingerprint.at("correct_metric").get<std::string>());
  options.correct_threshold = fingerprint.at("correct_threshold").get<double>();
  options.min_precision = fingerprint.at("min_precision").get<double>();
  options.seed = fingerprint.at("seed").get<std::uint64_t>();
  return options;
}

// The by-visibility tables and JSON in OUT/folder (report/by_visibility.hpp; layouts in
// batch/table_layouts.hpp).
Json write_by_visibility(const fs::path& out_dir, const std::string& folder,
                         const report::ByVisibilityAnalysis& analysis) {
  const std::pair<const batch::TableLayout*, std::string> tables[] = {
      {&batch::by_visibility_recall_table(), report::format_visibility_recall_csv(analysis)},
      {&batch::by_visibility_recall_thresholds_table(),
       report::format_visibility_recall_thresholds_csv(analysis)},
      {&batch::by_visibility_curve_table(), report::format_visibility_curve_csv(analysis)},
      {&batch::by_visibility_correlation_table(), report::format_error_correlation_csv(analysis)},
      {&batch::score_sweep_table(), report::format_score_sweep_csv(analysis)},
      {&batch::score_recommendation_table(), report::format_score_recommendation_csv(analysis)}};
  Json files = Json::array();
  for (const auto& [layout, text] : tables) {
    batch::write_output_file(out_dir, folder + layout->file_name, text);
    files.push_back(folder + layout->file_name);
  }
  batch::write_output_file(out_dir, folder + "by_visibility.json",
                           report::by_visibility_json(analysis).dump(2) + "\n");
  files.push_back(folder + "by_visibility.json");
  return files;
}

// Collects the evaluated estimates of every results file over the images, in item order, and
// at the end writes scores.json and the by-visibility outputs and returns summary.json.
class EvaluateSummary : public batch::SummaryBuilder {
 public:
  EvaluateSummary(Json fingerprint, fs::path out_dir)
      : fingerprint_(std::move(fingerprint)),
        out_dir_(std::move(out_dir)),
        metrics_(metrics_of(fingerprint_.at("errors"))),
        by_visibility_(by_visibility_options(fingerprint_.at("by_visibility"))) {
    for (const Json& file : fingerprint_.at("results")) {
      files_.emplace_back();
      files_.back().name = file.at("name").get<std::string>();
      for (const PoseMetric metric : metrics_) {
        files_.back().metrics.push_back({metric, taus_of(metric), {}});
        files_.back().metrics.back().per_tau.resize(taus_of(metric).size());
      }
    }
  }

  void add(const batch::ItemRecord& record) override {
    if (!record.ok) return;
    ++images_;
    estimator::BopImageErrors image;
    image.scene_id = record.key.scene_id;
    image.im_id = record.key.im_id;
    for (const Json& instance : record.summary.at("gt")) {
      image.gt.push_back({instance.at(0).get<int>(), instance.at(1).get<double>()});
    }
    for (const Json& target : record.summary.at("targets")) {
      image.targets[target.at(0).get<int>()] = target.at(1).get<int>();
      targets_ += target.at(1).get<int>();
    }
    const Json& files = record.summary.at("files");
    for (std::size_t f = 0; f < files_.size(); ++f) {
      FileScores& file = files_[f];
      file.estimates_in_images += files[f].at("estimates_in_image").get<long>();
      file.evaluated += static_cast<long>(files[f].at("evaluated").size());
      for (MetricImages& metric : file.metrics) {
        for (std::size_t t = 0; t < metric.taus.size(); ++t) {
          metric.per_tau[t].push_back(image_errors(image, files[f], metric.metric, t));
        }
      }
    }
  }

  Json finish(const batch::BatchTotals& totals) override {
    Json scores = Json::object(), overview = Json::object(), counts = Json::object();
    for (std::size_t f = 0; f < files_.size(); ++f) {
      const Json& entry = fingerprint_.at("results").at(f);
      Json file_scores = scores_of(files_[f]);
      file_scores["bop19_average_time_per_image"] = entry.at("average_time_per_image_s");
      Json brief = Json::object();
      for (const char* name :
           {"bop19_average_recall", "bop19_average_recall_vsd", "bop19_average_recall_mssd",
            "bop19_average_recall_mspd", "bop19_average_time_per_image"}) {
        if (file_scores.contains(name)) brief[name] = file_scores[name];
      }
      overview[files_[f].name] = brief;
      counts[files_[f].name] = {{"estimates_in_file", entry.at("estimates")},
                                {"estimates_in_evaluated_images", files_[f].estimates_in_images},
                                {"estimates_evaluated", files_[f].evaluated}};
      scores[files_[f].name] = std::move(file_scores);
    }
    batch::write_output_file(out_dir_, "scores.json", batch::dump_json(scores));

    std::vector<report::MethodTargets> methods;
    for (const FileScores& file : files_) methods.push_back(method_targets(file));
    const Json by_visibility_files =
        write_by_visibility(out_dir_, "", report::analyse_by_visibility(methods, by_visibility_));
    Json scene_visibility_files;
    if (fingerprint_.contains("scene_visibility")) {
      scene_visibility_files = write_by_scene_visibility(&methods);
    }

    Json summary;
    summary["command"] = "evaluate";
    summary["options"] = fingerprint_;
    summary["counts"] = totals.to_json();
    summary["counts"]["images_evaluated"] = images_;
    summary["counts"]["targets"] = targets_;
    summary["counts"]["results"] = counts;
    summary["scores"] = overview;
    summary["by_visibility"] = {
        {"files", by_visibility_files},
        {"visibility", "visib_fract"},
        {"scene_visibility",
         "not computed: a BOP dataset does not give the Eq. 10 scene visibility, and computing "
         "it renders every GT instance (`clutterscope visibility` writes it to images.csv)"}};
    if (!scene_visibility_files.is_null()) {
      summary["by_visibility"]["scene_visibility"] = {
          {"files", scene_visibility_files},
          {"images_csv", fingerprint_.at("scene_visibility").at("file")}};
    }
    summary["note"] =
        "BOP 2019 evaluation (bop_toolkit eval_bop19_pose.py): scores.json holds, per results "
        "file, the average recalls, the recall per threshold (VSD and MSSD: fraction of the "
        "object diameter, VSD per tau; MSPD: px at 640 px image width) and per object. "
        "bop19_average_recall (the mean of AR_VSD, AR_MSSD, AR_MSPD) is null unless all three "
        "are computed. The by_visibility*.csv and score_*.csv tables and by_visibility.json join "
        "each counted target's bop19 visib_fract (scene_gt_info.json) to the errors of the "
        "estimate paired with it; scene visibility (Eq. 10) is left undefined (see "
        "by_visibility.scene_visibility). Images that failed under --keep-going are missing "
        "from the recalls and the tables (counts.failures)";
    return summary;
  }

 private:
  // One error type over the images in item order: per tau (one for MSSD and MSPD) the
  // BopImageErrors of every image.
  struct MetricImages {
    PoseMetric metric = PoseMetric::kMssd;
    std::vector<double> taus;
    std::vector<std::vector<estimator::BopImageErrors>> per_tau;
  };
  struct FileScores {
    std::string name;
    std::vector<MetricImages> metrics;  // in metrics_ order
    long estimates_in_images = 0, evaluated = 0;
  };

  // The errors of one metric (VSD: at tau index t) of one results file in one image.
  static estimator::BopImageErrors image_errors(const estimator::BopImageErrors& image,
                                                const Json& file, PoseMetric metric,
                                                std::size_t t) {
    estimator::BopImageErrors errors = image;
    const char* key = report::to_string(metric);
    for (const Json& estimate : file.at("evaluated")) {
      estimator::BopEstimateErrors e{
          estimate.at("est_id").get<int>(), estimate.at("score").get<double>(), {}};
      const Json& gt_ids = estimate.at("gt_ids");
      const Json& values = estimate.at(key);
      for (std::size_t k = 0; k < gt_ids.size(); ++k) {
        const Json& value = metric == PoseMetric::kVsd ? values.at(k).at(t) : values.at(k);
        e.errors.emplace_back(gt_ids[k].get<int>(), error_of(value));
      }
      errors.estimates[estimate.at("obj_id").get<int>()].push_back(std::move(e));
    }
    return errors;
  }

  Json scores_of(const FileScores& file) const {
    Json scores = Json::object();
    Json recalls = Json::object();
    std::map<int, Json> per_object;
    std::vector<double> average_recalls;
    for (const MetricImages& metric : file.metrics) {
      const std::string type = report::to_string(metric.metric);
      std::map<int, std::vector<estimator::BopRecall>> objects;
      std::vector<estimator::BopRecall> overall;
      Json entries = Json::array();
      for (std::size_t t = 0; t < metric.taus.size(); ++t) {
        add_recall_entries(metric.per_tau[t], score_thresholds(metric.metric), metric.taus[t],
                           &objects, &overall, &entries);
      }
      recalls[type] = std::move(entries);
      // AR: the mean over every (tau, threshold) recall (VSD: 100, MSSD and MSPD: 10).
      average_recalls.push_back(estimator::bop_average_recall(overall));
      scores["bop19_average_recall_" + type] = average_recalls.back();
      for (const auto& [obj_id, object] : objects) {
        per_object[obj_id]["bop19_average_recall_" + type] = estimator::bop_average_recall(object);
        per_object[obj_id]["targets_count"] = object.front().targets_count;
      }
    }
    // eval_bop19_pose.py's mean of AR_VSD, AR_MSSD and AR_MSPD: defined with all three only.
    scores["bop19_average_recall"] =
        file.metrics.size() == 3 ? Json(estimator::bop_mean(average_recalls)) : Json(nullptr);
    scores["recalls"] = recalls;
    Json objects = Json::object();
    for (auto& [obj_id, entry] : per_object) objects[std::to_string(obj_id)] = entry;
    scores["per_object"] = objects;
    return scores;
  }

  // The analysis by the Eq. 10 scene visibility of each target's image (images.csv of
  // `clutterscope visibility`, named in the fingerprint) in OUT/by_scene_visibility/.
  Json write_by_scene_visibility(std::vector<report::MethodTargets>* methods) const {
    const fs::path images_csv = fingerprint_.at("scene_visibility").at("file").get<std::string>();
    // images.csv keys images by the split's folder, as ImageKey does.
    const std::string split = fingerprint_.at("scene_visibility").at("split").get<std::string>();
    std::map<std::pair<int, int>, double> scene_visibility;
    for (const report::ImageVisibilityRow& row : report::read_images_csv(images_csv)) {
      if (row.split == split && row.scene_visibility) {
        scene_visibility[{row.scene_id, row.im_id}] = *row.scene_visibility;
      }
    }
    for (report::MethodTargets& method : *methods) {
      for (report::TargetOutcome& target : method.targets) {
        const auto found = scene_visibility.find({target.scene_id, target.im_id});
        if (found != scene_visibility.end()) target.scene_visibility = found->second;
      }
    }
    report::ByVisibilityOptions options = by_visibility_;
    options.visibility = report::VisibilityMeasure::kScene;
    return write_by_visibility(out_dir_, "by_scene_visibility/",
                               report::analyse_by_visibility(*methods, options));
  }

  const MetricImages& metric_images(const FileScores& file, PoseMetric metric) const {
    for (const MetricImages& images : file.metrics) {
      if (images.metric == metric) return images;
    }
    throw std::logic_error(std::string("evaluate: ") + report::to_string(metric) +
                           " was not computed");
  }

  // The targets of one results file for the analysis by visibility: every counted GT instance
  // of every evaluated image, the estimate paired with it (by_visibility.hpp's rule, on the
  // error of the correctness rule's metric) and BOP's own match at every threshold.
  report::MethodTargets method_targets(const FileScores& file) const {
    report::MethodTargets method{file.name, {}};
    const MetricImages& pairing = metric_images(file, by_visibility_.correct_metric);
    for (std::size_t i = 0; i < pairing.per_tau.front().size(); ++i) {
      const estimator::BopImageErrors& image = pairing.per_tau.front()[i];
      const std::vector<bool> valid =
          estimator::bop_valid_gt(image.gt, image.targets, kBop19VisibGtMin);
      const int gt_count = static_cast<int>(image.gt.size());
      for (const auto& target : image.targets) {
        const int obj_id = target.first;
        const std::vector<int> paired = pair_estimates(pairing, i, obj_id, valid, gt_count);
        // recalled[metric][cell][k]: BOP's match at each (tau, threshold) cell.
        std::map<PoseMetric, std::vector<std::vector<int>>> matches;
        for (const MetricImages& metric : file.metrics) {
          for (std::size_t t = 0; t < metric.taus.size(); ++t) {
            const std::vector<estimator::BopEstimateErrors>& estimates =
                estimates_of(metric.per_tau[t][i], obj_id);
            for (const double threshold : score_thresholds(metric.metric)) {
              matches[metric.metric].push_back(
                  estimator::bop_match(estimates, valid, threshold, gt_count));
            }
          }
        }
        for (int k = 0; k < gt_count; ++k) {
          if (!valid[k] || image.gt[k].obj_id != obj_id) continue;
          report::TargetOutcome outcome;
          outcome.scene_id = image.scene_id;
          outcome.im_id = image.im_id;
          outcome.obj_id = obj_id;
          outcome.gt_id = k;
          outcome.visib_fract = image.gt[k].visib_fract;
          if (paired[k] >= 0) outcome.estimate = target_estimate(file, i, obj_id, paired[k], k);
          for (const auto& [metric, cells] : matches) {
            std::vector<bool>& recalled = outcome.bop_recalled[metric];
            for (const std::vector<int>& cell : cells) recalled.push_back(cell[k] >= 0);
          }
          method.targets.push_back(std::move(outcome));
        }
      }
    }
    return method;
  }

  static const std::vector<estimator::BopEstimateErrors>& estimates_of(
      const estimator::BopImageErrors& image, int obj_id) {
    static const std::vector<estimator::BopEstimateErrors> kNone;
    const auto found = image.estimates.find(obj_id);
    return found == image.estimates.end() ? kNone : found->second;
  }

  // by_visibility.hpp's pairing: pose_matching's greedy order without a threshold (by
  // decreasing score each estimate takes the free counted instance with the lowest error) on
  // the rule's metric, VSD's error being its mean over the taus. An infinite error is a
  // wrong pose, not no pose: it pairs too, after every finite one (bop_match counts only
  // errors below its threshold). Per GT instance the paired est_id, or -1.
  static std::vector<int> pair_estimates(const MetricImages& metric, std::size_t i, int obj_id,
                                         const std::vector<bool>& valid, int gt_count) {
    std::vector<estimator::BopEstimateErrors> estimates =
        estimates_of(metric.per_tau.front()[i], obj_id);
    for (std::size_t e = 0; e < estimates.size(); ++e) {
      for (std::size_t g = 0; g < estimates[e].errors.size(); ++g) {
        double error = 0;
        for (const auto& per_tau : metric.per_tau) {
          error += estimates_of(per_tau[i], obj_id)[e].errors[g].second;
        }
        error /= static_cast<double>(metric.per_tau.size());
        estimates[e].errors[g].second =
            std::isfinite(error) ? error : std::numeric_limits<double>::max();
      }
    }
    return estimator::bop_match(estimates, valid, HUGE_VAL, gt_count);
  }

  // The errors of estimate est_id of obj_id against GT instance k in image i, per metric.
  static report::TargetEstimate target_estimate(const FileScores& file, std::size_t i, int obj_id,
                                                int est_id, int k) {
    report::TargetEstimate estimate;
    for (const MetricImages& metric : file.metrics) {
      for (std::size_t t = 0; t < metric.taus.size(); ++t) {
        for (const estimator::BopEstimateErrors& e : estimates_of(metric.per_tau[t][i], obj_id)) {
          if (e.est_id != est_id) continue;
          estimate.score = e.score;
          for (const auto& [gt_id, error] : e.errors) {
            if (gt_id != k) continue;
            if (metric.metric == PoseMetric::kVsd) estimate.vsd.push_back(error);
            if (metric.metric == PoseMetric::kMssd) estimate.mssd = error;
            if (metric.metric == PoseMetric::kMspd) estimate.mspd = error;
          }
        }
      }
    }
    return estimate;
  }

  Json fingerprint_;
  fs::path out_dir_;
  std::vector<PoseMetric> metrics_;
  report::ByVisibilityOptions by_visibility_;
  std::vector<FileScores> files_;
  long images_ = 0, targets_ = 0;
};

std::string stem_of(const std::string& file) { return fs::path(file).stem().string(); }

// Reads every results file and refuses lines naming an object or image the dataset lacks.
std::vector<ResultsFile> read_results(const EvaluateJobOptions& options,
                                      const datasets::BopDataset& dataset) {
  std::vector<int> obj_ids;
  for (const datasets::ModelInfo& model : dataset.models()) obj_ids.push_back(model.obj_id);
  std::sort(obj_ids.begin(), obj_ids.end());
  datasets::DatasetSelection split;
  split.splits = {batch::split_folder(options.dataset)};
  const std::vector<datasets::ImageKey> images = dataset.list_images(split);
  std::vector<ResultsFile> files;
  for (const std::string& name : options.results) {
    ResultsFile file{stem_of(name), fs::path(name), datasets::read_bop_results(name), {}};
    datasets::check_bop_results_in_dataset(file.estimates, file.path, obj_ids, images);
    for (const datasets::PoseEstimate& estimate : file.estimates) {
      file.by_image[{estimate.scene_id, estimate.im_id}][estimate.obj_id].push_back(&estimate);
    }
    files.push_back(std::move(file));
  }
  return files;
}

// delta_mm: VSD's delta when VSD is computed.
Json evaluate_fingerprint(const EvaluateJobOptions& options, const std::vector<ResultsFile>& files,
                          std::optional<double> delta_mm) {
  Json fingerprint = batch::dataset_fingerprint(options.dataset);
  fingerprint["errors"] = options.errors;
  fingerprint["visib_gt_min"] = kBop19VisibGtMin;
  fingerprint["max_sym_disc_step"] = estimator::kBopMaxSymDiscStep;
  if (delta_mm) fingerprint["vsd_delta_mm"] = *delta_mm;
  fingerprint["by_visibility"] = by_visibility_fingerprint(options.by_visibility);
  Json results = Json::array();
  for (const ResultsFile& file : files) {
    // The content identifies the job (a changed file is another job); the counts and the time
    // are what the scores need of the whole file.
    results.push_back(
        {{"name", file.name},
         {"file", fs::absolute(file.path).string()},
         {"xxh64", batch::format_hex64(batch::xxh64(datasets::read_file(file.path)))},
         {"estimates", file.estimates.size()},
         {"average_time_per_image_s", datasets::bop19_average_time_per_image(file.estimates)}});
  }
  fingerprint["results"] = results;
  if (!options.scene_visibility_images.empty()) {
    const fs::path images = options.scene_visibility_images;
    fingerprint["scene_visibility"] = {
        {"file", fs::absolute(images).string()},
        {"split", batch::split_folder(options.dataset)},
        {"xxh64", batch::format_hex64(batch::xxh64(datasets::read_file(images)))}};
  }
  return fingerprint;
}

// The dataset's name as bop_toolkit knows datasets: the DATASET folder's name.
std::string dataset_name(const std::string& dataset) {
  fs::path path = fs::absolute(dataset).lexically_normal();
  if (!path.has_filename()) path = path.parent_path();
  return path.filename().string();
}

// VSD's delta: --vsd-delta-mm, else eval_bop19_pose.py's for the dataset's name.
double vsd_delta_mm(const EvaluateJobOptions& options) {
  if (options.vsd_delta_mm) return *options.vsd_delta_mm;
  const std::string name = dataset_name(options.dataset.dataset);
  const std::optional<double> delta = bop19_vsd_delta_mm(name);
  if (!delta) {
    throw batch::UsageError(
        "--vsd-delta-mm: VSD's delta depends on the dataset and bop_toolkit sets it by the "
        "dataset's name, but '" +
        name +
        "' (the name of the DATASET folder) is none of its names (itodd: 5 mm; hb, icbin, icmi, "
        "lm, lmo, ruapc, tless, tudl, tyol, ycbv, hope: 15 mm). Pass --vsd-delta-mm MM, or "
        "leave VSD out with --errors mssd,mspd");
  }
  return *delta;
}

// Resolves the default --errors and checks that VSD has a depth image for every target image:
// explicit vsd without one is bad input (DatasetError naming the file); the default then
// computes MSSD and MSPD only and says so on stderr.
std::vector<std::string> resolve_errors(const EvaluateJobOptions& options,
                                        const datasets::BopDataset& dataset,
                                        const std::vector<datasets::ImageKey>& items,
                                        bool say_on_stderr) {
  const bool by_default = options.errors.empty();
  std::vector<std::string> errors = options.errors;
  if (by_default) errors = {"vsd", "mssd", "mspd"};
  if (!has(errors, "vsd")) return errors;
  std::optional<datasets::ImageKey> first_missing;
  std::size_t missing = 0;
  for (const datasets::ImageKey& key : items) {
    if (!datasets::bop_depth_path(dataset.root(), key).empty()) continue;
    if (!first_missing) first_missing = key;
    ++missing;
  }
  if (!first_missing) return errors;
  const fs::path file = expected_depth_path(dataset.root(), *first_missing);
  const std::string counts = std::to_string(missing) + " of the " + std::to_string(items.size()) +
                             " target images have no depth image (depth/IMID.png or .tif)";
  if (!by_default) {
    throw datasets::DatasetError(
        file, datasets::location(first_missing->scene_id, first_missing->im_id) +
                  "missing: --errors vsd needs the measured depth image of every target image "
                  "(VSD compares renders with it); " +
                  counts + ". Leave VSD out with --errors mssd,mspd");
  }
  if (!say_on_stderr) return {"mssd", "mspd"};
  std::fprintf(stderr,
               "evaluate: errors mssd,mspd only, without VSD: %s is missing (%s); "
               "bop19_average_recall stays null\n",
               file.string().c_str(), counts.c_str());
  return {"mssd", "mspd"};
}

}  // namespace

void EvaluateStageTimes::add(const EvaluateStageTimes& other) {
  load_s += other.load_s;
  vsd_s += other.vsd_s;
  mssd_s += other.mssd_s;
  mspd_s += other.mspd_s;
  images += other.images;
  estimates += other.estimates;
  pairs += other.pairs;
  vsd_renders += other.vsd_renders;
  vsd_skipped_pairs += other.vsd_skipped_pairs;
}

bool EvaluateJobOptions::IsValid(std::string* why) const {
  if (results.empty()) {
    *why = "--results: at least one BOP results file (scene_id,im_id,obj_id,score,R,t,time)";
    return false;
  }
  std::set<std::string> stems;
  for (const std::string& file : results) {
    if (!stems.insert(stem_of(file)).second) {
      *why = "--results: two files named " + stem_of(file) +
             ".csv; the outputs are keyed by the file name without .csv, so give each file "
             "another name";
      return false;
    }
  }
  std::set<std::string> seen;
  for (const std::string& error : errors) {
    if (!report::pose_metric_from_string(error)) {
      *why = "--errors: unknown error '" + error + "'; choose among vsd, mssd, mspd";
      return false;
    }
    if (!seen.insert(error).second) {
      *why = "--errors: " + error + " given twice";
      return false;
    }
  }
  if (vsd_delta_mm) {
    BopVsdOptions vsd;
    vsd.delta_mm = *vsd_delta_mm;
    std::string reason;
    if (!vsd.IsValid(&reason)) {
      *why = "--vsd-delta-mm: " + reason;
      return false;
    }
  }
  std::string reason;
  if (!by_visibility.IsValid(&reason)) {
    *why = "by visibility (--visibility-bands, --correct, --min-precision): " + reason;
    return false;
  }
  return true;
}

batch::BatchOutputSpec evaluate_output_spec() {
  batch::BatchOutputSpec spec;
  spec.command = "evaluate";
  spec.tables = {batch::evaluate_errors_table().spec()};
  spec.make_summary = [](const Json& fingerprint, const fs::path& out_dir) {
    return std::make_unique<EvaluateSummary>(fingerprint, out_dir);
  };
  return spec;
}

namespace {

// run_evaluate_job, or with check_only its checks alone (nothing written, nothing said).
batch::BatchResult evaluate(const EvaluateJobOptions& options, bool check_only,
                            const RunControl& control) {
  std::string why;
  if (!options.IsValid(&why)) throw batch::UsageError(why);
  EvaluateJobOptions job_options = options;
  batch::DatasetOptions& dataset_options = job_options.dataset;
  std::error_code error;
  if (job_options.prefer_models_eval && dataset_options.models_dir == "models" &&
      fs::is_regular_file(fs::path(dataset_options.dataset) / "models_eval" / "models_info.json",
                          error)) {
    dataset_options.models_dir = "models_eval";
  }
  if (dataset_options.targets.empty()) {
    const fs::path shipped = fs::path(dataset_options.dataset) / kBop19TargetsFile;
    if (!fs::is_regular_file(shipped, error)) {
      throw batch::UsageError(
          "evaluate needs the BOP 2019 test targets: " + shipped.string() +
          " does not exist; pass --targets FILE (bop_toolkit's test_targets_bop19.json)");
    }
    dataset_options.targets = shipped.string();
  }
  datasets::TestTargets targets = datasets::read_test_targets(dataset_options.targets);
  if (!targets.per_object) {
    throw batch::UsageError("--targets " + dataset_options.targets +
                            ": lists images only (BOP 2024 targets); the BOP 2019 pose "
                            "evaluation needs obj_id and inst_count per target "
                            "(test_targets_bop19.json)");
  }
  // The checks of the results need every image of the split, before the targets restrict it.
  batch::DatasetOptions without_targets = dataset_options;
  without_targets.targets.clear();
  datasets::BopDataset dataset = batch::open_dataset(without_targets);
  const std::vector<ResultsFile> files = read_results(job_options, dataset);
  dataset.attach_targets(targets, dataset_options.targets);
  const std::map<int, datasets::ModelSymmetries> symmetries = datasets::read_model_symmetries(
      dataset.root() / dataset_options.models_dir / "models_info.json");

  batch::BatchJob job;
  const batch::BatchOutputSpec output = evaluate_output_spec();
  job.output = &output;
  job.items = batch::list_selected_images(dataset, dataset_options);
  // The errors over every selected image, not a shard's: shards of one job must agree.
  job_options.errors = resolve_errors(job_options, dataset, job.items, !check_only);
  // Errors in a fixed order, so that "mspd,mssd" and "mssd,mspd" are the same job.
  std::sort(job_options.errors.begin(), job_options.errors.end(),
            [](const std::string& a, const std::string& b) {
              return *report::pose_metric_from_string(a) < *report::pose_metric_from_string(b);
            });
  const bool vsd = has(job_options.errors, "vsd");
  const PoseMetric rule = job_options.by_visibility.correct_metric;
  if (!has(job_options.errors, report::to_string(rule))) {
    std::string computed;
    for (const std::string& name : job_options.errors) {
      computed += (computed.empty() ? "" : ",") + name;
    }
    throw batch::UsageError(
        std::string("--correct: the correctness rule of the analysis by visibility (default "
                    "mssd:0.1) is on ") +
        report::to_string(rule) + ", which is not computed (errors " + computed +
        "); pass --correct METRIC:THRESHOLD with a computed metric, e.g. --correct " +
        computed.substr(0, computed.find(',')) + ":" +
        (computed.rfind("mspd", 0) == 0 ? "20" : "0.3"));
  }
  std::optional<BopVsdOptions> vsd_options;
  if (vsd) {
    vsd_options.emplace();
    vsd_options->delta_mm = vsd_delta_mm(job_options);
    vsd_options->render_windows = job_options.vsd_render_windows;
  }
  if (check_only) {
    // The run finds a missing scene_gt_info.json per image (a failed image under --keep-going);
    // a front end running other steps first wants it before.
    for (const datasets::ImageKey& key : job.items) {
      require_scene_gt_info(dataset, key.split, key.scene_id);
    }
    return {};
  }
  job.fingerprint = evaluate_fingerprint(
      job_options, files,
      vsd_options ? std::optional<double>(vsd_options->delta_mm) : std::nullopt);
  const batch::ImageDigest image_digest = batch::bop_image_digest(dataset);
  job.input_digest = [&dataset, image_digest, vsd](const datasets::ImageKey& key,
                                                   batch::FileDigestCache& cache) {
    batch::Xxh64 digest;
    // VSD reads the depth image, which the image digest leaves out.
    const fs::path depth = vsd ? datasets::bop_depth_path(dataset.root(), key) : fs::path();
    const std::uint64_t parts[3] = {
        image_digest(key, cache),
        cache.digest(scene_gt_info_path(dataset, key.split, key.scene_id)),
        depth.empty() ? 0 : cache.digest(depth)};
    digest.update(parts, sizeof(parts));
    return digest.digest();
  };
  job.make_worker = [&dataset, &job_options, &files, &targets, &symmetries,
                     &vsd_options]() -> batch::ItemFunction {
    auto worker = std::make_shared<EvaluateWorker>(dataset, job_options, files, targets, symmetries,
                                                   vsd_options);
    return [worker](const datasets::ImageKey& key) { return worker->run(key); };
  };
  const batch::BatchOptions batch_options =
      control.apply(batch::batch_options_of(dataset_options, "evaluate"), "evaluate");
  if (!vsd) return batch::run_batch(job, batch_options);
  // Set before the workers create their GL contexts (see render/context.hpp).
  const render::WorkerRasterisationScope rasterisation;
  batch::BatchResult result = batch::run_batch(job, batch_options);
  batch::record_renderer(dataset_options.out, render::renderer_in_use());
  return result;
}

}  // namespace

JobSummary run_evaluate(const EvaluateJobOptions& options, const RunControl& control) {
  return job_summary(evaluate_output_spec(), options.dataset.out,
                     evaluate(options, false, control));
}

batch::BatchResult run_evaluate_job(const EvaluateJobOptions& options) {
  RunControl control;
  control.keep_results = false;
  return run_evaluate(options, control).run;
}

void check_evaluate_job(const EvaluateJobOptions& options) { evaluate(options, true, {}); }

}  // namespace clutterscope::jobs
