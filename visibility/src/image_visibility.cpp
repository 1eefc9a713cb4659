#include <algorithm>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <sstream>

namespace clutterscope::visibility {

std::string to_string(VisibilityMode mode) {
  switch (mode) {
    case VisibilityMode::kRendered:
      return "rendered";
    case VisibilityMode::kBop19:
      return "bop19";
    case VisibilityMode::kBop18:
      return "bop18";
  }
  return "rendered";
}

std::optional<VisibilityMode> parse_visibility_mode(const std::string& text) {
  if (text == "rendered") return VisibilityMode::kRendered;
  if (text == "bop19") return VisibilityMode::kBop19;
  if (text == "bop18") return VisibilityMode::kBop18;
  return std::nullopt;
}

bool VisibilityOptions::IsValid(std::string* why) const {
  BopVisibilityOptions bop;
  bop.delta_mm = delta_mm;
  return bop.IsValid(why);
}

double near_plane_m() { return render::Intrinsics{}.near_m; }

void check_drawable(const datasets::Camera& camera, int canvas_factor, int max_target_size,
                    const std::string& where) {
  const long long width = static_cast<long long>(camera.width) * canvas_factor;
  const long long height = static_cast<long long>(camera.height) * canvas_factor;
  if (width <= max_target_size && height <= max_target_size) return;
  std::ostringstream message;
  message << where << "the image is " << camera.width << "x" << camera.height << " pixels";
  if (canvas_factor > 1) {
    message << ", drawn on a " << canvas_factor << "W x " << canvas_factor << "H canvas of "
            << width << "x" << height;
  }
  message << ": beyond this renderer's limit of " << max_target_size
          << " pixels per side (GL_MAX_RENDERBUFFER_SIZE, GL_MAX_VIEWPORT_DIMS, "
             "GL_MAX_TEXTURE_SIZE); images up to "
          << max_target_size / canvas_factor << " pixels per side can be drawn";
  throw datasets::DatasetError("", message.str());
}

namespace {

void check_in_front_of_camera(const std::vector<render::Instance>& objects, double near_m,
                              const std::string& where) {
  for (std::size_t i = 0; i < objects.size(); ++i) {
    if (objects[i].mesh == nullptr) throw std::invalid_argument("instance without a mesh");
    const Eigen::AlignedBox3f& bounds = objects[i].mesh->bounds();
    double nearest = std::numeric_limits<double>::infinity();
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3f corner = bounds.corner(static_cast<Eigen::AlignedBox3f::CornerType>(c));
      nearest = std::min(nearest, (objects[i].model_to_camera * corner.cast<double>()).z());
    }
    if (!(nearest > near_m)) {
      std::ostringstream message;
      message << where << "gt " << i << ": the object reaches behind the camera (nearest "
              << "bounding-box corner at z = " << nearest * 1000.0
              << " mm, must be beyond the near plane at " << near_m * 1000.0
              << " mm); its visibility cannot be rendered";
      throw datasets::DatasetError("", message.str());
    }
  }
}

std::vector<render::Instance> labelled(const std::vector<render::Instance>& objects) {
  std::vector<render::Instance> instances = objects;
  for (std::size_t i = 0; i < instances.size(); ++i) {
    instances[i].label = static_cast<std::uint32_t>(i + 1);
  }
  return instances;
}

void compute_rendered(render::Renderer& renderer, const render::Intrinsics& intrinsics,
                      const std::vector<render::Instance>& instances, ImageVisibility* result,
                      ImageMasks* masks) {
  render::CountOptions count_options;
  count_options.canvas_factor = kVisibilityCanvasFactor;
  const std::vector<render::InstanceCounts> counts =
      renderer.count_visibility(intrinsics, instances, count_options);
  for (std::size_t i = 0; i < instances.size(); ++i) {
    ObjectVisibility& object = result->objects[i];
    object.counts = {counts[i].silhouette_px, counts[i].visible_px};
    object.in_view = counts[i].silhouette_px > 0;
    BopGtInfo& info = object.info;
    info.px_count_all = counts[i].canvas_silhouette_px;
    info.px_count_valid = counts[i].silhouette_px;
    info.px_count_visib = counts[i].visible_px;
    info.visib_fract = object_visibility(counts[i].visible_px, counts[i].silhouette_px);
    if (info.px_count_visib > 0) {  // bop_toolkit's rule for both boxes
      info.bbox_obj = to_bop_box(counts[i].canvas_silhouette_bbox);
      info.bbox_visib = to_bop_box(counts[i].visible_bbox);
    }
  }
  if (!masks) return;
  const render::DepthLabelImage scene = renderer.render(intrinsics, instances);
  renderer.render_each_alone(intrinsics, instances, [&](const render::AloneView& view) {
    cv::Mat silhouette(intrinsics.height, intrinsics.width, CV_8U, cv::Scalar(0));
    if (!view.rect.empty()) silhouette(view.rect).setTo(255, view.depth > 0);
    masks->silhouette[view.index] = silhouette;
    masks->visible[view.index] = scene.labels == static_cast<int>(view.index + 1);
  });
}

// scene = the nearer of scene and object where the object has depth (0 = none).
void nearest_surface(const cv::Mat& object, cv::Mat scene) {
  for (int v = 0; v < object.rows; ++v) {
    const float* in = object.ptr<float>(v);
    float* out = scene.ptr<float>(v);
    for (int u = 0; u < object.cols; ++u) {
      if (in[u] > 0 && (out[u] == 0 || in[u] < out[u])) out[u] = in[u];
    }
  }
}

// bop_toolkit renders each object alone on the 3W x 3H canvas with renderer_vispy and crops
// the image out of it; BopDepthRenderer does the same with the same numbers, rasterising only
// each object's projected rectangle on that canvas.
void compute_bop(render::BopDepthRenderer& renderer, const datasets::Camera& camera,
                 const std::vector<BopObject>& objects, const VisibilityOptions& options,
                 const cv::Mat& measured_depth_mm, ImageVisibility* result, ImageMasks* masks,
                 cv::Mat* gt_depth_mm) {
  const int width = camera.width, height = camera.height;
  const BopCamera bop_camera{camera.fx(), camera.fy(), camera.cx(), camera.cy()};
  const BopVisibilityOptions bop_options{
      options.mode == VisibilityMode::kBop19 ? BopMode::kBop19 : BopMode::kBop18, options.delta_mm};
  // calc_gt_info.py: cx + ren_cx_offset, cy + ren_cy_offset on a 3W x 3H renderer (plus half
  // a pixel for cameras whose K projects to integer pixel centres).
  const double shift = options.pixel_center == render::PixelCenter::kInteger ? 0.5 : 0.0;
  const render::BopTarget canvas{
      camera.fx(), camera.fy(), camera.cx() + width + shift, camera.cy() + height + shift,
      3 * width,   3 * height};
  const cv::Rect image_on_canvas(width, height, width, height);
  // The measured distances once per image; per object, only its window is processed.
  const cv::Mat test_distance = visibility::depth_to_distance(measured_depth_mm, bop_camera);
  if (gt_depth_mm) *gt_depth_mm = cv::Mat(height, width, CV_32F, cv::Scalar(0));
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const BopObject& object = objects[i];
    const cv::Rect rect =
        render::BopDepthRenderer::projected_rect(*object.model, object.R, object.t, canvas);
    const cv::Mat depth = renderer.render_object(*object.model, object.R, object.t, canvas, rect);
    const CanvasRender cut = cut_canvas_render(depth, rect, image_on_canvas);
    const cv::Rect& window = cut.window;  // image coordinates
    const cv::Mat& model_mm = cut.model_mm;
    if (gt_depth_mm) nearest_surface(model_mm, (*gt_depth_mm)(window));
    cv::Mat visib;
    ObjectVisibility& result_object = result->objects[i];
    result_object.info =
        compute_bop_gt_info_in_window(model_mm, window, cut.silhouette, test_distance, bop_camera,
                                      bop_options, masks ? &visib : nullptr);
    // V^s in BOP modes: sum px_count_visib / sum px_count_all, the px_count_all-weighted
    // mean of visib_fract.
    // An object out of view has px_count_all > 0 when its silhouette reaches the 3W x 3H
    // canvas: it is kept out of V^s, as in rendered mode.
    result_object.in_view = cv::countNonZero(model_mm) > 0;
    if (result_object.in_view) {
      result_object.counts = {result_object.info.px_count_all, result_object.info.px_count_visib};
    }
    if (masks) {
      cv::Mat silhouette_mask(height, width, CV_8U, cv::Scalar(0));
      cv::Mat visible_mask(height, width, CV_8U, cv::Scalar(0));
      silhouette_mask(window).setTo(255, model_mm > 0);
      visible_mask(window).setTo(255, visib);
      masks->silhouette[i] = silhouette_mask;
      masks->visible[i] = visible_mask;
    }
  }
}

ImageVisibility finish(ImageVisibility result) {
  std::vector<Eq10Counts> counts;
  for (const ObjectVisibility& object : result.objects) counts.push_back(object.counts);
  result.scene_visibility = scene_visibility(counts);
  return result;
}

void prepare_masks(std::size_t objects, ImageMasks* masks) {
  if (!masks) return;
  masks->silhouette.assign(objects, cv::Mat());
  masks->visible.assign(objects, cv::Mat());
}

}  // namespace

ImageVisibility compute_image_visibility(render::Renderer& renderer, const datasets::Camera& camera,
                                         const std::vector<render::Instance>& objects,
                                         const VisibilityOptions& options, const std::string& where,
                                         ImageMasks* masks) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  if (options.is_bop()) {
    throw std::invalid_argument(
        "compute_image_visibility computes the rendered mode; BOP modes need "
        "compute_bop_image_visibility");
  }
  check_drawable(camera, kVisibilityCanvasFactor, renderer.max_target_size(), where);
  const render::Intrinsics intrinsics =
      render::Intrinsics::from_camera(camera, options.pixel_center);
  check_in_front_of_camera(objects, intrinsics.near_m, where);
  ImageVisibility result;
  result.objects.resize(objects.size());
  prepare_masks(objects.size(), masks);
  if (objects.empty()) return result;
  compute_rendered(renderer, intrinsics, labelled(objects), &result, masks);
  return finish(std::move(result));
}

ImageVisibility compute_bop_image_visibility(render::BopDepthRenderer& renderer,
                                             const datasets::Camera& camera,
                                             const std::vector<BopObject>& objects,
                                             const VisibilityOptions& options,
                                             const cv::Mat& measured_depth_mm,
                                             const std::string& where, ImageMasks* masks,
                                             cv::Mat* gt_depth_mm) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  if (!options.is_bop()) {
    throw std::invalid_argument("compute_bop_image_visibility needs a BOP mode (bop19, bop18)");
  }
  check_drawable(camera, kVisibilityCanvasFactor, renderer.max_target_size(), where);
  const double near_mm = near_plane_m() * 1000.0;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const BopObject& object = objects[i];
    if (object.model == nullptr) throw std::invalid_argument("BOP object without a model");
    double nearest = std::numeric_limits<double>::infinity();
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d& min = object.model->bbox_min();
      const Eigen::Vector3d& size = object.model->bbox_size();
      const Eigen::Vector3d corner((c & 4) ? min.x() + size.x() : min.x(),
                                   (c & 2) ? min.y() + size.y() : min.y(),
                                   (c & 1) ? min.z() + size.z() : min.z());
      nearest = std::min(nearest, (object.R * corner + object.t).z());
    }
    if (!(nearest > near_mm)) {
      std::ostringstream message;
      message << where << "gt " << i << ": the object reaches behind the camera (nearest "
              << "bounding-box corner at z = " << nearest << " mm, must be beyond the near plane "
              << "at " << near_mm << " mm); its visibility cannot be rendered";
      throw datasets::DatasetError("", message.str());
    }
  }
  if (measured_depth_mm.type() != CV_32F || measured_depth_mm.cols != camera.width ||
      measured_depth_mm.rows != camera.height) {
    throw datasets::DatasetError("", where + "BOP visibility needs the measured depth (" +
                                         std::to_string(camera.width) + "x" +
                                         std::to_string(camera.height) + ", mm)");
  }
  ImageVisibility result;
  result.objects.resize(objects.size());
  prepare_masks(objects.size(), masks);
  if (gt_depth_mm) *gt_depth_mm = cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(0));
  if (objects.empty()) return result;
  compute_bop(renderer, camera, objects, options, measured_depth_mm, &result, masks, gt_depth_mm);
  return finish(std::move(result));
}

}  // namespace clutterscope::visibility
