// `clutterscope render`: the GT depth and instance-label images of one dataset image, rendered
// headless with EGL, plus a colourised preview.

#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/model_cache.hpp>
#include <clutterscope/render/renderer.hpp>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "commands.hpp"

namespace clutterscope::cli {

namespace fs = std::filesystem;

namespace {

struct RenderArguments {
  DatasetOptions dataset;  // DATASET, --split, --split-type, --models-dir, --targets
  int scene = -1;
  int image = -1;
  std::string out;
  std::string pixel_center = "half";
};

void write_png(const fs::path& path, const cv::Mat& image) {
  std::vector<unsigned char> bytes;
  if (!cv::imencode(".png", image, bytes)) {
    throw render::RenderError(path.string() + ": PNG encoding failed");
  }
  datasets::write_file_atomically(path, std::string(bytes.begin(), bytes.end()));
}

// BOP depth: 16-bit millimetres (depth_scale 1), 0 = no surface.
cv::Mat depth_to_millimetres(const cv::Mat& depth_m, int* clipped) {
  cv::Mat millimetres(depth_m.size(), CV_16U);
  *clipped = 0;
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* in = depth_m.ptr<float>(y);
    auto* out = millimetres.ptr<std::uint16_t>(y);
    for (int x = 0; x < depth_m.cols; ++x) {
      const double mm = std::round(static_cast<double>(in[x]) * 1000.0);
      if (mm > 65535.0) ++*clipped;
      out[x] = static_cast<std::uint16_t>(std::clamp(mm, 0.0, 65535.0));
    }
  }
  return millimetres;
}

// Depth colourised over the range of the rendered surfaces (near = warm), black background,
// white outlines where the front instance changes.
cv::Mat preview(const render::DepthLabelImage& image) {
  const cv::Mat foreground = image.depth > 0;
  double near_m = 0, far_m = 0;
  cv::Mat colour(image.depth.size(), CV_8UC3, cv::Scalar::all(0));
  if (cv::countNonZero(foreground) > 0) {
    cv::minMaxLoc(image.depth, &near_m, &far_m, nullptr, nullptr, foreground);
    cv::Mat scaled;
    const double range = std::max(far_m - near_m, 1e-6);
    image.depth.convertTo(scaled, CV_8U, -255.0 / range, 255.0 * far_m / range);
    cv::applyColorMap(scaled, colour, cv::COLORMAP_TURBO);
    colour.setTo(cv::Scalar::all(0), ~foreground);
  }
  for (int y = 0; y < image.labels.rows; ++y) {
    const auto* row = image.labels.ptr<std::int32_t>(y);
    const auto* below = image.labels.ptr<std::int32_t>(std::min(y + 1, image.labels.rows - 1));
    for (int x = 0; x < image.labels.cols; ++x) {
      const std::int32_t right = row[std::min(x + 1, image.labels.cols - 1)];
      if (row[x] != right || row[x] != below[x]) {
        colour.at<cv::Vec3b>(y, x) = cv::Vec3b(255, 255, 255);
      }
    }
  }
  return colour;
}

void run_render(const RenderArguments& arguments) {
  batch::claim_output_folder(arguments.out, "render");
  const datasets::BopDataset dataset = open_dataset(arguments.dataset);
  datasets::DatasetSelection selection;
  selection.splits = {split_folder(arguments.dataset)};
  selection.scene_ids = {arguments.scene};
  selection.image_ids = {arguments.image};
  const std::vector<datasets::ImageKey> keys = dataset.list_images(selection);
  if (keys.size() != 1) {
    throw datasets::DatasetError(
        dataset.root(), datasets::location(arguments.scene, arguments.image) +
                            "expected one image in split " + selection.splits.front() +
                            (arguments.dataset.targets.empty() ? "" : " and the --targets") +
                            ", found " + std::to_string(keys.size()));
  }
  const datasets::SceneView view = dataset.load(keys.front());

  const render::EglContext context = render::EglContext::create();
  std::cout << "GL renderer: " << context.renderer() << " (" << context.version() << ")\n";
  render::Renderer renderer(context);
  render::ModelCache models(dataset);
  const std::vector<render::Instance> instances = render::scene_instances(view, models);
  const render::PixelCenter center = arguments.pixel_center == "integer"
                                         ? render::PixelCenter::kInteger
                                         : render::PixelCenter::kHalfPixel;
  const render::DepthLabelImage image =
      renderer.render(render::Intrinsics::from_camera(view.camera, center), instances);

  const fs::path out = arguments.out;
  batch::mark_output_folder(out, "render");
  int clipped = 0;
  const cv::Mat depth_mm = depth_to_millimetres(image.depth, &clipped);
  cv::Mat labels;
  image.labels.convertTo(labels, CV_16U);  // GT index + 1; the reader caps instances far below
  write_png(out / "depth.png", depth_mm);
  write_png(out / "labels.png", labels);
  write_png(out / "preview.png", preview(image));

  std::cout << "split " << view.key.split << ", scene " << view.key.scene_id << ", image "
            << view.key.im_id << ": "
            << batch::count_text(static_cast<long long>(instances.size()), "object") << ", "
            << view.camera.width << "x" << view.camera.height << ", pixel centres "
            << (center == render::PixelCenter::kInteger ? "integer" : "half") << ", "
            << batch::count_text(cv::countNonZero(image.labels), "object pixel") << "\n";
  if (clipped > 0) {
    std::cout << "warning: " << batch::count_text(clipped, "pixel")
              << " deeper than 65.535 m clipped in depth.png\n";
  }
  std::cout << "wrote " << (out / "depth.png").string() << ", " << (out / "labels.png").string()
            << ", " << (out / "preview.png").string() << "\n";
}

}  // namespace

void add_render_command(CLI::App& app, int* exit_code) {
  auto arguments = std::make_shared<RenderArguments>();
  CLI::App* command = app.add_subcommand(
      "render",
      "Render the ground truth of one image headless (EGL): depth.png (16-bit millimetres, as "
      "BOP depth with depth_scale 1, 0 = no surface), labels.png (16-bit, 0 = background, k+1 = "
      "GT instance k of scene_gt.json) and preview.png (depth colourised near = red to far = "
      "blue, white instance outlines). Prints the GL renderer in use.");
  add_dataset_options(*command, &arguments->dataset, kDataset);
  command->add_option("--scene", arguments->scene, "scene id")
      ->required()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--image", arguments->image, "image id within the scene")
      ->required()
      ->check(CLI::NonNegativeNumber);
  command->add_option("--out", arguments->out, "output folder (created if missing)")->required();
  command
      ->add_option("--pixel-center", arguments->pixel_center,
                   "where pixel (u, v) samples the image: half = K projects to (u + 0.5, v + 0.5) "
                   "(GL, bop_toolkit's renderer), integer = to (u, v) (OpenCV, BlenderProc)")
      ->check(CLI::IsMember({"half", "integer"}))
      ->capture_default_str();
  command->callback([arguments, exit_code] {
    run_render(*arguments);
    *exit_code = 0;
  });
}

}  // namespace clutterscope::cli
