#include <algorithm>
#include <clutterscope/render/renderer.hpp>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include "renderer_state.hpp"

// Renderer::count_visibility: Eq. 10's per-instance pixel counts from one pass over the
// geometry.

namespace clutterscope::render {
namespace {

// Running bounding rectangle of pixel coordinates.
struct PixelBounds {
  int min_x = std::numeric_limits<int>::max(), min_y = std::numeric_limits<int>::max();
  int max_x = std::numeric_limits<int>::min(), max_y = std::numeric_limits<int>::min();
  void add(int x, int y) {
    min_x = std::min(min_x, x);
    max_x = std::max(max_x, x);
    min_y = std::min(min_y, y);
    max_y = std::max(max_y, y);
  }
  cv::Rect rect(int offset_x, int offset_y) const {
    if (max_x < min_x) return {};
    return {min_x + offset_x, min_y + offset_y, max_x - min_x + 1, max_y - min_y + 1};
  }
};

// Counts from a per-pixel coverage bit mask over `region` (layers of 32 instances,
// `coverage[(layer * rows + y) * cols + x]`) and the front labels (instance index + 1) of the
// image window `image_in_region`. Output rects are in image coordinates.
std::vector<InstanceCounts> count_from_masks(const std::vector<std::uint32_t>& coverage, int layers,
                                             cv::Size region, const cv::Mat& front_labels,
                                             cv::Rect image_in_region, std::size_t instances) {
  std::vector<InstanceCounts> counts(instances);
  std::vector<PixelBounds> silhouette(instances), visible(instances), canvas(instances);
  const std::size_t plane = static_cast<std::size_t>(region.width) * region.height;
  for (int layer = 0; layer < layers; ++layer) {
    const std::uint32_t* bits = coverage.data() + plane * layer;
    for (int y = 0; y < region.height; ++y) {
      const bool row_in_image = y >= image_in_region.y && y < image_in_region.br().y;
      const std::uint32_t* row = bits + static_cast<std::size_t>(y) * region.width;
      for (int x = 0; x < region.width; ++x) {
        std::uint32_t mask = row[x];
        if (mask == 0) continue;
        const bool in_image = row_in_image && x >= image_in_region.x && x < image_in_region.br().x;
        while (mask != 0) {
          const int bit = __builtin_ctz(mask);
          mask &= mask - 1;
          const std::size_t i = static_cast<std::size_t>(layer) * 32 + bit;
          ++counts[i].canvas_silhouette_px;
          canvas[i].add(x, y);
          if (in_image) {
            ++counts[i].silhouette_px;
            silhouette[i].add(x, y);
          }
        }
      }
    }
  }
  for (int y = 0; y < front_labels.rows; ++y) {
    const auto* row = front_labels.ptr<std::int32_t>(y);
    for (int x = 0; x < front_labels.cols; ++x) {
      if (row[x] <= 0) continue;
      const auto i = static_cast<std::size_t>(row[x] - 1);
      ++counts[i].visible_px;
      visible[i].add(x, y);
    }
  }
  for (std::size_t i = 0; i < instances; ++i) {
    counts[i].silhouette_bbox = silhouette[i].rect(-image_in_region.x, -image_in_region.y);
    counts[i].canvas_silhouette_bbox = canvas[i].rect(-image_in_region.x, -image_in_region.y);
    counts[i].visible_bbox = visible[i].rect(0, 0);
  }
  return counts;
}

// Pre-4.5 fallback of count_visibility: each object alone into `coverage`, then the scene for
// the front labels over `image_in_region`.
cv::Mat count_by_separate_renders(Renderer& renderer, const Intrinsics& target,
                                  const std::vector<Instance>& instances, cv::Size region,
                                  cv::Rect image_in_region, std::vector<std::uint32_t>* coverage) {
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const DepthLabelImage alone = renderer.render(target, {instances[i]});
    std::uint32_t* plane =
        coverage->data() + static_cast<std::size_t>(region.width) * region.height * (i / 32);
    for (int y = 0; y < region.height; ++y) {
      const float* depth = alone.depth.ptr<float>(y);
      for (int x = 0; x < region.width; ++x) {
        if (depth[x] > 0) plane[static_cast<std::size_t>(y) * region.width + x] |= 1u << (i % 32);
      }
    }
  }
  std::vector<Instance> indexed = instances;
  for (std::size_t i = 0; i < indexed.size(); ++i) {
    indexed[i].label = static_cast<std::uint32_t>(i + 1);
  }
  const DepthLabelImage scene = renderer.render(target, indexed);
  return scene.labels(image_in_region);
}

}  // namespace

void Renderer::State::ensure_coverage_image(int width, int height, int layers) {
  if (width > coverage_width || height > coverage_height || layers > coverage_layers) {
    coverage_width = std::max(width, coverage_width);
    coverage_height = std::max(height, coverage_height);
    coverage_layers = std::max(layers, coverage_layers);
    coverage_image = gl::make_texture();
    glBindTexture(GL_TEXTURE_2D_ARRAY, coverage_image.get());
    glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_R32UI, coverage_width, coverage_height,
                   coverage_layers);
    gl::check_error("coverage image allocation");
  }
}

cv::Mat Renderer::State::draw_coverage(const Intrinsics& target,
                                       const std::vector<Instance>& instances, cv::Size region,
                                       cv::Rect image_in_region, int layers,
                                       std::vector<std::uint32_t>* coverage) {
  ensure_coverage_image(region.width, region.height, layers);
  const GLuint zero = 0;
  glClearTexSubImage(coverage_image.get(), 0, 0, 0, 0, region.width, region.height, layers,
                     GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  glBindImageTexture(0, coverage_image.get(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_R32UI);

  begin(region.width, region.height);
  glColorMaski(0, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);  // only labels are read back
  const detail::Program& program = this->coverage;
  glUseProgram(program.program.get());
  set_projection(program, target, {0, 0});
  const GpuMesh::State* bound = nullptr;
  for (std::size_t i = 0; i < instances.size(); ++i) {
    glUniform1i(program.coverage_layer, static_cast<GLint>(i / 32));
    glUniform1ui(program.coverage_bit, 1u << (i % 32));
    // A closed mesh's silhouette and front surface are its front faces: skipping the back
    // faces halves the fragments this pass shades (it has no early depth test).
    const int orientation = instances[i].mesh->state_->prepared->closed_orientation;
    FaceSelection front = FaceSelection::kAll;
    if (orientation != 0) {
      glEnable(GL_CULL_FACE);
      glFrontFace(orientation > 0 ? GL_CW : GL_CCW);  // the y-down projection flips winding
      front = orientation > 0 ? FaceSelection::kClockwise : FaceSelection::kCounterClockwise;
    } else {
      glDisable(GL_CULL_FACE);
    }
    draw(program, instances[i], static_cast<std::uint32_t>(i + 1), &bound, front);
  }
  glDisable(GL_CULL_FACE);
  glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
  cv::Mat front_labels = read_labels(image_in_region.x, image_in_region.y, image_in_region.width,
                                     image_in_region.height);
  glGetTextureSubImage(coverage_image.get(), 0, 0, 0, 0, region.width, region.height, layers,
                       GL_RED_INTEGER, GL_UNSIGNED_INT,
                       static_cast<GLsizei>(coverage->size() * sizeof(std::uint32_t)),
                       coverage->data());
  glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl::check_error("count_visibility");
  return front_labels;
}

std::vector<InstanceCounts> Renderer::count_visibility(const Intrinsics& intrinsics,
                                                       const std::vector<Instance>& instances,
                                                       const CountOptions& options) {
  intrinsics.validate();
  detail::check_instances(instances);
  if (options.canvas_factor < 1 || options.canvas_factor % 2 == 0) {
    throw std::invalid_argument("CountOptions::canvas_factor must be odd and >= 1, got " +
                                std::to_string(options.canvas_factor));
  }
  if (instances.size() >= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    throw std::invalid_argument("count_visibility: too many instances");
  }
  if (instances.empty()) return {};

  // Render only the part of the canvas that the image and the objects' projections reach.
  const Intrinsics canvas = intrinsics.enlarged(options.canvas_factor);
  const int margin = (options.canvas_factor - 1) / 2;
  const cv::Rect image_on_canvas(margin * intrinsics.width, margin * intrinsics.height,
                                 intrinsics.width, intrinsics.height);
  cv::Rect region = image_on_canvas;
  if (options.canvas_factor > 1) {
    for (const auto& instance : instances) region |= projected_rect(canvas, instance);
  }
  const Intrinsics target = canvas.crop(region.x, region.y, region.width, region.height);
  const cv::Rect image_in_region = image_on_canvas - region.tl();
  const int layers = static_cast<int>((instances.size() + 31) / 32);
  std::vector<std::uint32_t> coverage(static_cast<std::size_t>(region.width) * region.height *
                                      layers);
  const cv::Mat front_labels =
      state_->coverage_supported
          ? state_->draw_coverage(target, instances, region.size(), image_in_region, layers,
                                  &coverage)
          : count_by_separate_renders(*this, target, instances, region.size(), image_in_region,
                                      &coverage);
  return count_from_masks(coverage, layers, region.size(), front_labels, image_in_region,
                          instances.size());
}

}  // namespace clutterscope::render
