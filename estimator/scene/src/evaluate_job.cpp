#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/input_digest.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/bop_gt_info.hpp>
#include <clutterscope/datasets/bop_pose_models.hpp>
#include <clutterscope/datasets/bop_results.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/estimator/bop_pose_errors.hpp>
#include <clutterscope/estimator/bop_scores.hpp>
#include <clutterscope/scene_estimation/evaluate_job.hpp>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace clutterscope::scene_estimation {

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

// A normalised error for the per-item summary: JSON has no infinity, so a non-finite error
// (MSSD's shortcut, an MSPD through depth 0) is null, which never matches, as inf and NaN never
// match in bop_toolkit.
Json error_json(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }
double error_of(const Json& value) { return value.is_null() ? HUGE_VAL : value.get<double>(); }

fs::path scene_gt_info_path(const datasets::BopDataset& dataset, const std::string& split,
                            int scene_id) {
  return dataset.root() / split / datasets::six_digits(scene_id) / "scene_gt_info.json";
}

class EvaluateWorker {
 public:
  EvaluateWorker(const datasets::BopDataset& dataset, const EvaluateJobOptions& job,
                 const std::vector<ResultsFile>& files, const datasets::TestTargets& targets,
                 const std::map<int, datasets::ModelSymmetries>& symmetries)
      : dataset_(dataset),
        files_(files),
        targets_(targets),
        symmetries_(symmetries),
        mssd_(has(job.errors, "mssd")),
        mspd_(has(job.errors, "mspd")) {}

  batch::ItemOutput run(const datasets::ImageKey& key) {
    const datasets::SceneView view = dataset_.load(key);
    const std::vector<double>& visib_fract = visib_fract_of(key, view);
    const std::map<int, int>& targets = targets_.images.at({key.scene_id, key.im_id});
    std::vector<estimator::BopGtInstance> gt;
    for (std::size_t k = 0; k < view.objects.size(); ++k) {
      gt.push_back({view.objects[k].obj_id, visib_fract[k]});
    }
    const std::vector<bool> valid = estimator::bop_valid_gt(gt, targets, kBop19VisibGtMin);

    Json gt_json = Json::array(), targets_json = Json::array(), files_json = Json::array();
    for (const auto& instance : gt) gt_json.push_back({instance.obj_id, instance.visib_fract});
    for (const auto& [obj_id, inst_count] : targets) targets_json.push_back({obj_id, inst_count});
    std::string rows;
    for (const ResultsFile& file : files_) {
      files_json.push_back(evaluate_file(file, key, view, gt, valid, targets, &rows));
    }
    batch::ItemOutput output;
    output.tables = {rows};
    output.summary = {{"gt", gt_json}, {"targets", targets_json}, {"files", files_json}};
    return output;
  }

 private:
  // The evaluated estimates of one results file in this image: errors.csv rows, and for the
  // scores {"estimates_in_image", "evaluated": [{obj_id, est_id, score, gt_ids, mssd, mspd}]}
  // with the errors normalised as their thresholds are.
  Json evaluate_file(const ResultsFile& file, const datasets::ImageKey& key,
                     const datasets::SceneView& view,
                     const std::vector<estimator::BopGtInstance>& gt,
                     const std::vector<bool>& valid, const std::map<int, int>& targets,
                     std::string* rows) {
    Json evaluated = Json::array();
    std::size_t in_image = 0;
    const auto image = file.by_image.find({key.scene_id, key.im_id});
    if (image != file.by_image.end()) {
      for (const auto& entry : image->second) in_image += entry.second.size();
    }
    // MSPD thresholds are for 640 px wide images (eval_calc_scores.py).
    const double width_factor = 640.0 / view.camera.width;
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
        Json gt_ids = Json::array(), mssd = Json::array(), mspd = Json::array();
        for (std::size_t k = 0; k < view.objects.size(); ++k) {
          if (view.objects[k].obj_id != obj_id) continue;
          const Eigen::Isometry3d& pose = view.objects[k].model_to_camera;
          double mssd_m = HUGE_VAL, mspd_px = HUGE_VAL;
          batch::CsvRow row;
          row.add(file.name).add(key.scene_id).add(key.im_id).add(obj_id).add(est_id);
          row.add(static_cast<int>(k)).add(batch::format_shortest(estimate.score));
          row.add(batch::format_shortest(gt[k].visib_fract)).add(valid[k] ? "1" : "0");
          if (mssd_) {
            mssd_m = estimator::bop_mssd(estimate.model_to_camera, pose, model.points,
                                         model.symmetries, model.diameter_m);
            mssd.push_back(error_json(mssd_m / model.diameter_m));
          }
          if (mspd_) {
            mspd_px = estimator::mspd(estimate.model_to_camera, pose, view.camera.K, model.points,
                                      model.symmetries);
            mspd.push_back(error_json(mspd_px * width_factor));
          }
          // Empty: not computed (not in --errors, or MSSD's centres a diameter or more apart,
          // which bop_toolkit records as inf) or not finite (an MSPD through depth 0).
          row.add(mssd_ ? batch::format_shortest(1e3 * mssd_m) : "");
          row.add(mspd_ ? batch::format_shortest(mspd_px) : "");
          *rows += row.str();
          gt_ids.push_back(k);
        }
        evaluated.push_back({{"obj_id", obj_id},
                             {"est_id", est_id},
                             {"score", estimate.score},
                             {"gt_ids", gt_ids},
                             {"mssd", mssd},
                             {"mspd", mspd}});
      }
    }
    return {{"estimates_in_image", in_image}, {"evaluated", evaluated}};
  }

  // scene_gt_info.json's visib_fract of every GT instance (one scene kept per worker).
  const std::vector<double>& visib_fract_of(const datasets::ImageKey& key,
                                            const datasets::SceneView& view) {
    const fs::path path = scene_gt_info_path(dataset_, key.split, key.scene_id);
    if (scene_id_ != key.scene_id || scene_split_ != key.split) {
      std::error_code error;
      if (!fs::is_regular_file(path, error)) {
        throw datasets::DatasetError(
            path,
            "missing: evaluate needs the bop19 visib_fract of every GT instance, which "
            "decides the GT instances that count (bop_toolkit's calc_gt_info.py writes "
            "it; so does `clutterscope visibility --mode bop19 --write-bop-info`)");
      }
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
  std::map<int, ModelData> models_;
  int scene_id_ = -1;
  std::string scene_split_;
  std::map<int, std::vector<double>> scene_visib_;
};

// The recalls of one error type over `images`, in scores.json's layout: per threshold
// bop_toolkit's scores_th=*.json fields (obj_recalls: the recall of each target object).
Json recall_entries(const std::vector<estimator::BopImageErrors>& images,
                    const std::vector<double>& thresholds,
                    std::map<int, std::vector<estimator::BopRecall>>* per_object,
                    std::vector<estimator::BopRecall>* overall) {
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
  Json entries = Json::array();
  for (const double threshold : thresholds) {
    const estimator::BopRecall recall = estimator::bop_recall(images, threshold, kBop19VisibGtMin);
    overall->push_back(recall);
    Json obj_recalls = Json::object();
    for (const auto& [obj_id, only] : object_images) {
      const estimator::BopRecall object = estimator::bop_recall(only, threshold, kBop19VisibGtMin);
      (*per_object)[obj_id].push_back(object);
      obj_recalls[std::to_string(obj_id)] = object.recall;
    }
    entries.push_back({{"threshold", recall.threshold},
                       {"recall", recall.recall},
                       {"tp_count", recall.tp_count},
                       {"targets_count", recall.targets_count},
                       {"gt_count", recall.gt_count},
                       {"obj_recalls", obj_recalls}});
  }
  return entries;
}

// Collects the evaluated estimates of every results file over the images, in item order, and
// at the end writes scores.json and returns summary.json.
class EvaluateSummary : public batch::SummaryBuilder {
 public:
  EvaluateSummary(Json fingerprint, fs::path out_dir)
      : fingerprint_(std::move(fingerprint)), out_dir_(std::move(out_dir)) {
    for (const Json& file : fingerprint_.at("results")) {
      files_.emplace_back();
      files_.back().name = file.at("name").get<std::string>();
    }
    const Json& errors = fingerprint_.at("errors");
    mssd_ = std::find(errors.begin(), errors.end(), "mssd") != errors.end();
    mspd_ = std::find(errors.begin(), errors.end(), "mspd") != errors.end();
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
      estimator::BopImageErrors mssd = image, mspd = image;
      file.estimates_in_images += files[f].at("estimates_in_image").get<long>();
      for (const Json& estimate : files[f].at("evaluated")) {
        ++file.evaluated;
        const int obj_id = estimate.at("obj_id").get<int>();
        estimator::BopEstimateErrors m{
            estimate.at("est_id").get<int>(), estimate.at("score").get<double>(), {}};
        estimator::BopEstimateErrors p = m;
        const Json& gt_ids = estimate.at("gt_ids");
        for (std::size_t k = 0; k < gt_ids.size(); ++k) {
          const int gt_id = gt_ids[k].get<int>();
          if (mssd_) m.errors.emplace_back(gt_id, error_of(estimate.at("mssd").at(k)));
          if (mspd_) p.errors.emplace_back(gt_id, error_of(estimate.at("mspd").at(k)));
        }
        mssd.estimates[obj_id].push_back(std::move(m));
        mspd.estimates[obj_id].push_back(std::move(p));
      }
      file.mssd.push_back(std::move(mssd));
      file.mspd.push_back(std::move(mspd));
    }
  }

  Json finish(const batch::BatchTotals& totals) override {
    Json scores = Json::object(), overview = Json::object(), counts = Json::object();
    for (std::size_t f = 0; f < files_.size(); ++f) {
      const Json& entry = fingerprint_.at("results").at(f);
      Json file_scores = scores_of(files_[f]);
      file_scores["bop19_average_time_per_image"] = entry.at("average_time_per_image_s");
      Json brief = Json::object();
      for (const char* name : {"bop19_average_recall", "bop19_average_recall_mssd",
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
    Json summary;
    summary["command"] = "evaluate";
    summary["options"] = fingerprint_;
    summary["counts"] = totals.to_json();
    summary["counts"]["images_evaluated"] = images_;
    summary["counts"]["targets"] = targets_;
    summary["counts"]["results"] = counts;
    summary["scores"] = overview;
    summary["note"] =
        "BOP 2019 evaluation (bop_toolkit eval_bop19_pose.py): scores.json holds, per results "
        "file, the average recalls, the recall per threshold (MSSD: fraction of the object "
        "diameter; MSPD: px at 640 px image width) and per object. bop19_average_recall (the "
        "mean of AR_VSD, AR_MSSD, AR_MSPD) is null without VSD. Images that failed under "
        "--keep-going are missing from the recalls (counts.failures)";
    return summary;
  }

 private:
  struct FileScores {
    std::string name;
    std::vector<estimator::BopImageErrors> mssd, mspd;
    long estimates_in_images = 0, evaluated = 0;
  };

  Json scores_of(const FileScores& file) const {
    Json scores = Json::object();
    scores["bop19_average_recall"] = nullptr;  // needs VSD (not available yet)
    Json recalls = Json::object();
    std::map<int, Json> per_object;
    const auto add_type = [&](const char* type,
                              const std::vector<estimator::BopImageErrors>& images,
                              const std::vector<double>& thresholds) {
      std::map<int, std::vector<estimator::BopRecall>> objects;
      std::vector<estimator::BopRecall> overall;
      recalls[type] = recall_entries(images, thresholds, &objects, &overall);
      scores[std::string("bop19_average_recall_") + type] = estimator::bop_average_recall(overall);
      for (const auto& [obj_id, object] : objects) {
        per_object[obj_id][std::string("bop19_average_recall_") + type] =
            estimator::bop_average_recall(object);
        per_object[obj_id]["targets_count"] = object.front().targets_count;
      }
    };
    // VSD goes here when it is available: its errors per tau (per-item "vsd"), recalls per
    // (tau, threshold), AR_VSD their mean, and bop19_average_recall = bop_mean of the three.
    if (mssd_) add_type("mssd", file.mssd, estimator::bop19_fraction_thresholds());
    if (mspd_) add_type("mspd", file.mspd, estimator::bop19_mspd_thresholds_px());
    scores["recalls"] = recalls;
    Json objects = Json::object();
    for (auto& [obj_id, entry] : per_object) objects[std::to_string(obj_id)] = entry;
    scores["per_object"] = objects;
    return scores;
  }

  Json fingerprint_;
  fs::path out_dir_;
  std::vector<FileScores> files_;
  bool mssd_ = false, mspd_ = false;
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

Json evaluate_fingerprint(const EvaluateJobOptions& options,
                          const std::vector<ResultsFile>& files) {
  Json fingerprint = batch::dataset_fingerprint(options.dataset);
  fingerprint["errors"] = options.errors;
  fingerprint["visib_gt_min"] = kBop19VisibGtMin;
  fingerprint["max_sym_disc_step"] = estimator::kBopMaxSymDiscStep;
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
  return fingerprint;
}

}  // namespace

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
  if (errors.empty()) {
    *why = "--errors: at least one of mssd, mspd";
    return false;
  }
  std::set<std::string> seen;
  for (const std::string& error : errors) {
    if (error == "vsd") {
      *why =
          "--errors: vsd is not available yet (VSD renders every estimate against the depth "
          "images; it will come in a later version); choose among mssd, mspd, e.g. --errors "
          "mssd,mspd. Without VSD there is no bop19_average_recall, only AR_MSSD and AR_MSPD";
      return false;
    }
    if (error != "mssd" && error != "mspd") {
      *why = "--errors: unknown error '" + error + "'; choose among mssd, mspd";
      return false;
    }
    if (!seen.insert(error).second) {
      *why = "--errors: " + error + " given twice";
      return false;
    }
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

batch::BatchResult run_evaluate_job(const EvaluateJobOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw batch::UsageError(why);
  EvaluateJobOptions job_options = options;
  // Errors in a fixed order, so that "mspd,mssd" and "mssd,mspd" are the same job.
  std::sort(job_options.errors.begin(), job_options.errors.end(),
            [](const std::string& a, const std::string& b) { return a == "mssd" && b != "mssd"; });
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
  job.fingerprint = evaluate_fingerprint(job_options, files);
  const batch::ImageDigest image_digest = batch::bop_image_digest(dataset);
  job.input_digest = [&dataset, image_digest](const datasets::ImageKey& key,
                                              batch::FileDigestCache& cache) {
    batch::Xxh64 digest;
    const std::uint64_t parts[2] = {
        image_digest(key, cache),
        cache.digest(scene_gt_info_path(dataset, key.split, key.scene_id))};
    digest.update(parts, sizeof(parts));
    return digest.digest();
  };
  job.make_worker = [&dataset, &job_options, &files, &targets,
                     &symmetries]() -> batch::ItemFunction {
    auto worker =
        std::make_shared<EvaluateWorker>(dataset, job_options, files, targets, symmetries);
    return [worker](const datasets::ImageKey& key) { return worker->run(key); };
  };
  return batch::run_batch(job, batch::batch_options_of(dataset_options, "evaluate"));
}

}  // namespace clutterscope::scene_estimation
