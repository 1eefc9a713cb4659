#pragma once

// An independent CPU reference for visibility tests: oriented boxes ray cast through each
// pixel centre, with no GL code. Pixel (u, v) is the ray through (u + 0.5, v + 0.5) in the
// image plane of K (DESIGN §3, half-pixel convention). A pixel is "ambiguous" for an object
// when rays shifted by a small fraction of a pixel disagree about it (an edge passes within
// that distance of the pixel centre); rasterisers may decide those either way, so tests
// compare exactly only when no pixel is ambiguous, and within the ambiguous count otherwise.

#include <Eigen/Geometry>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/datasets/scene.hpp>
#include <clutterscope/visibility/bop_visibility.hpp>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace clutterscope::visibility::testing {

// A box of full extents `size` (metres) centred on its model origin, posed in the camera.
struct RayBox {
  Eigen::Vector3d size = Eigen::Vector3d::Ones();
  Eigen::Isometry3d model_to_camera = Eigen::Isometry3d::Identity();
};

// The same box as a triangle mesh (8 vertices, 12 triangles), for the renderer.
datasets::Mesh box_mesh(const Eigen::Vector3d& size);

struct RayCastObject {
  std::int64_t silhouette_px = 0;     // K_i: pixels of the image the box covers alone
  std::int64_t visible_px = 0;        // v_i: pixels where it is the nearest surface
  std::int64_t ambiguous_px = 0;      // image pixels whose K_i or v_i membership is uncertain
  std::int64_t canvas_px = 0;         // silhouette pixels on the 3W x 3H canvas
  std::int64_t canvas_ambiguous = 0;  // canvas pixels whose membership is uncertain
  cv::Rect canvas_bbox;               // canvas silhouette bbox, image coordinates
  cv::Rect visible_bbox;              // bbox of the visible pixels
  cv::Mat depth;                      // CV_32F Z in metres of the box alone (image), 0 = none
  cv::Mat silhouette;                 // CV_8U 255 where the box covers the pixel
  cv::Mat visible;                    // CV_8U 255 where the box is the nearest surface
  cv::Mat ambiguous;                  // CV_8U 255 where either may go both ways
};

struct RayCastScene {
  std::vector<RayCastObject> objects;
  cv::Mat depth;   // CV_32F scene Z in metres, 0 = background
  cv::Mat labels;  // CV_32S index + 1 of the nearest box, 0 = background
};

// Ray casts the boxes through every pixel of the camera's image and of the 3x canvas.
RayCastScene ray_cast(const datasets::Camera& camera, const std::vector<RayBox>& boxes);

// A camera of the given size with focal length f and the principal point at the centre.
datasets::Camera test_camera(int width, int height, double focal);

// A pose looking at the box from the camera: translation t (metres), rotation about the axis
// (normalised) by angle (radians).
Eigen::Isometry3d pose(const Eigen::Vector3d& t,
                       const Eigen::Vector3d& axis = Eigen::Vector3d::UnitZ(), double angle = 0.0);

}  // namespace clutterscope::visibility::testing
