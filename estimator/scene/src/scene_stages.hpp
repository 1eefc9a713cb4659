#pragma once

// The stages of SceneEstimator::estimate (paper §III), private to scene_estimation:
//   frame the scene -> observe -> match detections -> build the MRF -> NBP -> refine and fuse.
// Each stage reads the outputs of the ones before it and records what it finds (failures,
// where the graph, observation and detections came from) in the ViewEstimate.

#include <Eigen/Geometry>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/detector.hpp>
#include <clutterscope/datasets/scene.hpp>
#include <clutterscope/estimator/mixture.hpp>
#include <clutterscope/estimator/nbp.hpp>
#include <clutterscope/estimator/scorer.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/model_cache.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

namespace clutterscope::scene_estimation {

// One estimator's thread-bound state: its GL context and renderer, the models and scorer.
struct SceneEstimator::State {
  State(const datasets::BopDataset& data, const EstimateOptions& opts);

  // Surface points of a model for ICP, fixed per obj_id (seeded by the id).
  const Eigen::Matrix3Xd& model_points(int obj_id);
  // resolve_model_misfit of a split, resolved once per split.
  const ModelMisfit& misfit_of(const std::string& split_folder);

  const datasets::BopDataset& dataset;
  EstimateOptions options;
  ModelMisfit misfit;  // of the view being estimated (its split's misfit_of)
  std::map<std::string, ModelMisfit> misfits;
  datasets::DeclaredNoise noise;  // resolve_pixel_noise
  render::EglContext context;
  render::Renderer renderer;
  render::ModelCache models;
  std::shared_ptr<RenderHypothesisScorer> scorer;
  std::map<int, Eigen::Matrix3Xd> points;
};

// The scene graph, the fixed supports and the support frame, with every instance's model
// centre, support-frame position (GT) and extents.
struct SceneFrame {
  datasets::SceneGraph graph;
  std::vector<bool> is_fixed;  // per GT instance
  Eigen::Isometry3d support_to_camera = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d camera_to_support = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector3d> centre_model, position, extent;  // per GT instance
};

// What the estimator sees of the view: the depth (measured or synthetic), the detections
// (attached or synthetic) and the Eq. 10 counts of the GT instances.
struct ObservedView {
  render::Intrinsics image;
  cv::Mat depth;
  std::vector<datasets::Detection> detections;
  std::vector<render::InstanceCounts> counts;  // per GT instance
};

// A detection box matched to a GT instance: the clipped pixel box, the BOP bbox, the score and
// whether the box is amodal (a hidden object's unoccluded silhouette).
struct MatchedBox {
  cv::Rect box;
  Eigen::Vector4d bbox;
  double score = 0;
  bool amodal = false;
};

// The pairwise MRF of the view and where its GT instances went in it.
struct SceneMrf {
  estimator::PairwiseMrf mrf;
  std::vector<int> node_of;                         // per GT instance, -1: no node
  std::vector<estimator::GaussianMixture> initial;  // per GT instance, hidden nodes only
};

SceneFrame frame_scene(SceneEstimator::State& s, const datasets::SceneView& view,
                       ViewEstimate* result);

// Throws datasets::DatasetError for a measured observation without depth or with a wrong
// depth_scale.
ObservedView observe(SceneEstimator::State& s, const datasets::SceneView& view,
                     const SceneFrame& frame, ViewEstimate* result);

// The boxes of each GT instance (by obj_id; several instances of one obj_id take the boxes that
// overlap their projected model bounds best, detection_matching.hpp); a box overlapping no
// object of its class by options.min_detection_iou is counted in result->unmatched_detections.
std::vector<std::vector<MatchedBox>> match_detections(SceneEstimator::State& s,
                                                      const datasets::SceneView& view,
                                                      const SceneFrame& frame,
                                                      const ObservedView& observed,
                                                      ViewEstimate* result);

// Hidden nodes (one per estimable object, appended to result->objects for every non-fixed
// instance), fixed support nodes, support and non-contact edges. `rng` draws the initial
// mixtures.
SceneMrf build_mrf(SceneEstimator::State& s, const datasets::SceneView& view,
                   const SceneFrame& frame, const ObservedView& observed,
                   const std::vector<std::vector<MatchedBox>>& boxes, std::mt19937_64& rng,
                   ViewEstimate* result);

// NBP on the MRF; a degenerate MRF fails every object with a node (node_of set to -1).
estimator::NbpResult run_belief_propagation(SceneEstimator::State& s, SceneMrf* scene,
                                            std::mt19937_64& rng, ViewEstimate* result);

// Post-processing of each estimated object: K belief samples refined by ICP in the camera
// frame and fused (hidden objects: the belief's mean and spread), covariance, checks, errors.
void refine_and_fuse(SceneEstimator::State& s, const SceneFrame& frame, const SceneMrf& scene,
                     const estimator::NbpResult& nbp, std::mt19937_64& rng, ViewEstimate* result);

}  // namespace clutterscope::scene_estimation
