#include <gtest/gtest.h>

#include <algorithm>
#include <clutterscope/datasets/catalogue.hpp>
#include <clutterscope/datasets/generator.hpp>
#include <clutterscope/datasets/graph_inference.hpp>
#include <iterator>
#include <set>

namespace clutterscope::datasets {
namespace {

ModelInfo box_model(int obj_id, const std::string& label, const Eigen::Vector3d& size) {
  ModelInfo model;
  model.obj_id = obj_id;
  model.label = label;
  model.min = -size / 2;
  model.size = size;
  return model;
}

Eigen::Isometry3d at(double x, double y, double z, double yaw = 0) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Eigen::Vector3d(x, y, z));
  pose.rotate(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  return pose;
}

TEST(GraphInference, OverlapAreaOfSquaresMatchesHandComputation) {
  const ModelInfo unit = box_model(1, "a", Eigen::Vector3d(1, 1, 1));
  const SupportBox a = support_box(unit, at(0, 0, 0));
  const SupportBox b = support_box(unit, at(0.5, 0.25, 0));
  EXPECT_NEAR(convex_overlap_area(a.footprint, b.footprint), 0.5 * 0.75, 1e-12);
  // A square rotated 45 degrees about the same centre: overlap = octagon, 2 (sqrt 2 - 1).
  const SupportBox c = support_box(unit, at(0, 0, 0, M_PI / 4));
  EXPECT_NEAR(convex_overlap_area(a.footprint, c.footprint), 2 * (std::sqrt(2.0) - 1), 1e-12);
  const SupportBox far = support_box(unit, at(3, 0, 0));
  EXPECT_EQ(convex_overlap_area(a.footprint, far.footprint), 0.0);
}

TEST(GraphInference, ContactWithinDeltaAndOverlapMakesSupport) {
  const ModelInfo box = box_model(1, "box", Eigen::Vector3d(0.2, 0.1, 0.1));
  GraphInferenceOptions options;  // delta d = 5 mm
  const auto graph_of = [&](double gap, double shift) {
    std::vector<SupportBox> boxes = {support_box(box, at(0, 0, 0.05)),
                                     support_box(box, at(shift, 0, 0.15 + gap))};
    return infer_scene_graph(boxes, {}, options);
  };
  EXPECT_EQ(graph_of(0.003, 0.05).support, (std::vector<std::pair<int, int>>{{0, 1}}));
  EXPECT_EQ(graph_of(-0.003, 0.05).support, (std::vector<std::pair<int, int>>{{0, 1}}));
  EXPECT_TRUE(graph_of(0.008, 0.05).support.empty()) << "gap above delta d";
  EXPECT_TRUE(graph_of(0.0, 0.2005).support.empty()) << "footprints do not overlap";
  // Near but not in contact: a non_contact pair.
  EXPECT_EQ(graph_of(0.02, 0.05).non_contact, (std::vector<std::pair<int, int>>{{0, 1}}));
  EXPECT_TRUE(graph_of(0.2, 0.05).non_contact.empty()) << "farther than near distance";
}

TEST(GraphInference, LowestObjectRestsOnTheHighestFixedSupport) {
  const ModelInfo table = box_model(16, "table", Eigen::Vector3d(1.2, 0.8, 0.04));
  const ModelInfo tray = box_model(15, "tray", Eigen::Vector3d(0.46, 0.33, 0.045));
  const ModelInfo can = box_model(11, "soup_can", Eigen::Vector3d(0.067, 0.067, 0.101));
  std::vector<SupportBox> boxes = {
      support_box(table, at(0, 0, -0.02)), support_box(tray, at(0, 0, 0.0225)),
      support_box(can, at(0.1, 0, 0.012 + 0.0505)),  // on the tray floor
      support_box(can, at(0.45, 0.3, 0.0505)),       // on the table beside the tray
  };
  const SceneGraph graph = infer_scene_graph(boxes, {0, 1});
  EXPECT_EQ(graph.support, (std::vector<std::pair<int, int>>{{0, 1}, {0, 3}, {1, 2}}));
  EXPECT_EQ(graph.fixed, (std::vector<int>{0, 1}));
  EXPECT_TRUE(graph.inferred);
}

// A generated scene as a dataset view: poses in the camera frame of view 0.
SceneView as_view(const GeneratedScene& scene, bool with_world_pose) {
  SceneView view;
  view.camera = default_camera(640, 480);
  if (with_world_pose) view.camera.world_to_camera = scene.world_to_camera[0];
  for (const auto& object : scene.objects) {
    view.objects.push_back({object.obj_id, scene.world_to_camera[0] * object.model_to_world});
  }
  return view;
}

TEST(GraphInference, RecoversTheGeneratorsGraphOverTwoHundredScenes) {
  const auto catalogue = default_catalogue();
  std::vector<ModelInfo> models;
  for (const auto& item : catalogue) {
    models.push_back(model_info(item, tessellate(item, 500), "unused.ply"));
  }
  std::size_t truth_edges = 0, recovered = 0, false_edges = 0, world_frame_mismatch = 0;
  std::size_t non_contact_total = 0, non_contact_differing = 0;
  const Preset presets[] = {Preset::kTray, Preset::kPile, Preset::kShelf, Preset::kTray};
  for (int s = 0; s < 200; ++s) {
    LayoutOptions options;
    options.preset = presets[s % 4];
    options.min_objects = 4;
    options.max_objects = 12;
    options.max_stack = 4;
    std::mt19937_64 rng = derive_rng(424242, s, 0);
    const GeneratedScene scene = generate_layout(catalogue, options, rng);
    const SceneGraph inferred = infer_scene_graph(as_view(scene, true), models);
    const std::set<std::pair<int, int>> truth(scene.graph.support.begin(),
                                              scene.graph.support.end());
    truth_edges += truth.size();
    for (const auto& edge : inferred.support) {
      if (truth.count(edge)) {
        ++recovered;
      } else {
        ++false_edges;
        ADD_FAILURE() << "scene " << s << ": false support " << edge.first << " -> " << edge.second;
      }
    }
    EXPECT_EQ(inferred.fixed, scene.graph.fixed);
    non_contact_total += scene.graph.non_contact.size();
    std::vector<std::pair<int, int>> differing;
    std::set_symmetric_difference(inferred.non_contact.begin(), inferred.non_contact.end(),
                                  scene.graph.non_contact.begin(), scene.graph.non_contact.end(),
                                  std::back_inserter(differing));
    non_contact_differing += differing.size();
    // Without the camera's world pose the fixed table gives the gravity frame.
    const SceneGraph from_table = infer_scene_graph(as_view(scene, false), models);
    if (from_table.support != inferred.support) ++world_frame_mismatch;
  }
  const double recall = static_cast<double>(recovered) / truth_edges;
  std::cout << "support edges: " << truth_edges << ", recovered " << recovered << " (recall "
            << recall << "), false " << false_edges << "\n";
  EXPECT_GT(truth_edges, 1500u);
  EXPECT_GE(recall, 0.99);
  EXPECT_EQ(false_edges, 0u);
  EXPECT_EQ(world_frame_mismatch, 0u);
  // Boxes exactly near_distance apart (equal heights on the table) may flip by round-off.
  std::cout << "non_contact pairs: " << non_contact_total << ", differing " << non_contact_differing
            << "\n";
  EXPECT_LE(non_contact_differing, non_contact_total / 200);
}

TEST(GraphInference, GravityFrameFallsBackToTheFixedSupportThenTheCamera) {
  SceneView view;
  view.objects.push_back({16, at(0.1, 0.2, 1.0, 0.3)});
  GravitySource source;
  const Eigen::Isometry3d frame = gravity_frame(view, {0}, &source);
  EXPECT_EQ(source, GravitySource::kFixedSupport);
  EXPECT_TRUE(frame.isApprox(view.objects[0].model_to_camera));
  const Eigen::Isometry3d upright = gravity_frame(view, {}, &source);
  EXPECT_EQ(source, GravitySource::kUprightCamera);
  // World up is the camera's -y axis.
  EXPECT_TRUE((upright.linear() * Eigen::Vector3d::UnitZ()).isApprox(-Eigen::Vector3d::UnitY()));
  view.camera.world_to_camera = at(0, 0, 2);
  gravity_frame(view, {0}, &source);
  EXPECT_EQ(source, GravitySource::kCameraWorldPose);
}

TEST(GraphInference, UnknownModelNamesSceneAndInstance) {
  SceneView view;
  view.key.scene_id = 3;
  view.key.im_id = 12;
  view.objects.push_back({99, Eigen::Isometry3d::Identity()});
  try {
    infer_scene_graph(view, {});
    FAIL() << "expected DatasetError";
  } catch (const std::exception& error) {
    EXPECT_NE(std::string(error.what()).find("scene 3, image 12, gt 0: obj_id 99"),
              std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace clutterscope::datasets
