#include <cerrno>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>
#include <sstream>

#include "bop_json.hpp"

namespace clutterscope::datasets {

namespace fs = std::filesystem;
using detail::FieldContext;
using detail::Json;

namespace {

// Checks a value before it is written: outputs never hold NaN or infinity.
double finite(double value, const char* field, const FieldContext& context) {
  if (!std::isfinite(value)) context.fail(std::string(field) + " is not finite");
  return value;
}

Json row_major(const Eigen::Matrix3d& matrix, const char* field, const FieldContext& context) {
  Json values = Json::array();
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) values.push_back(finite(matrix(row, col), field, context));
  }
  return values;
}

Json millimetres(const Eigen::Vector3d& metres, const char* field, const FieldContext& context) {
  Json values = Json::array();
  for (int i = 0; i < 3; ++i) values.push_back(finite(metres[i] * 1000.0, field, context));
  return values;
}

Json index_pairs(const std::vector<std::pair<int, int>>& pairs) {
  Json values = Json::array();
  for (const auto& [first, second] : pairs) values.push_back(Json::array({first, second}));
  return values;
}

std::vector<unsigned char> encode_png(const cv::Mat& image, const fs::path& path) {
  std::vector<unsigned char> bytes;
  if (!cv::imencode(".png", image, bytes)) throw DatasetError(path, "PNG encoding failed");
  return bytes;
}

}  // namespace

std::string six_digits(int id) {
  char text[32];
  std::snprintf(text, sizeof(text), "%06d", id);
  return text;
}

void write_file_atomically(const fs::path& path, const std::string& contents) {
  if (path.has_parent_path()) create_folders(path.parent_path());
  // A unique temporary name in the same folder, so the rename is atomic and concurrent
  // writers of different files never collide.
  std::random_device entropy;
  const fs::path temporary =
      path.string() + ".tmp" + std::to_string(entropy()) + std::to_string(entropy());
  try {
    std::ofstream stream(temporary, std::ios::binary | std::ios::trunc);
    if (!stream) throw_write_error(path, errno);
    stream.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    close_checked(stream, path);
    rename_checked(temporary, path);
  } catch (...) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw;
  }
}

void write_depth_png(const fs::path& path, const cv::Mat& depth_m, double depth_scale) {
  if (!std::isfinite(depth_scale) || depth_scale <= 0) {
    throw DatasetError(path, "depth_scale must be positive and finite");
  }
  if (depth_m.type() != CV_32FC1) {
    throw DatasetError(path, "depth to write must be CV_32F metres with one channel");
  }
  cv::Mat raw(depth_m.size(), CV_16UC1);
  const double scale = 1000.0 / depth_scale;
  for (int v = 0; v < depth_m.rows; ++v) {
    for (int u = 0; u < depth_m.cols; ++u) {
      const double metres = depth_m.at<float>(v, u);
      const double value = std::round(metres * scale);
      if (!std::isfinite(metres) || metres < 0 || value > 65535) {
        std::ostringstream message;
        message << "pixel (" << u << ", " << v << "): depth " << metres
                << " m cannot be stored as 16-bit with depth_scale " << depth_scale;
        throw DatasetError(path, message.str());
      }
      raw.at<uint16_t>(v, u) = static_cast<uint16_t>(value);
    }
  }
  const std::vector<unsigned char> bytes = encode_png(raw, path);
  write_file_atomically(path, std::string(bytes.begin(), bytes.end()));
}

BopWriter::BopWriter(fs::path root) : root_(std::move(root)) {}

void BopWriter::write_models_info(const std::vector<ModelInfo>& models) const {
  const fs::path models_dir = root_ / "models";
  const fs::path info_path = models_dir / "models_info.json";
  std::map<int, Json> infos;
  std::map<int, Json> names;
  for (const ModelInfo& model : models) {
    const FieldContext context{info_path, "obj_id " + std::to_string(model.obj_id) + ": "};
    if (infos.count(model.obj_id) > 0) context.fail("obj_id appears twice");
    if (!(model.diameter > 0)) context.fail("diameter must be positive");
    Json info;
    info["diameter"] = finite(model.diameter * 1000.0, "diameter", context);
    const char* axes[] = {"x", "y", "z"};
    for (int axis = 0; axis < 3; ++axis) {
      const std::string min_field = std::string("min_") + axes[axis];
      const std::string size_field = std::string("size_") + axes[axis];
      info[min_field] = finite(model.min[axis] * 1000.0, min_field.c_str(), context);
      info[size_field] = finite(model.size[axis] * 1000.0, size_field.c_str(), context);
    }
    const fs::path default_mesh = models_dir / ("obj_" + six_digits(model.obj_id) + ".ply");
    if (!model.mesh_path.empty() &&
        model.mesh_path.lexically_normal() != default_mesh.lexically_normal()) {
      const fs::path relative = model.mesh_path.lexically_relative(models_dir);
      const bool inside = !relative.empty() && *relative.begin() != "..";
      info["file"] = (inside ? relative : fs::absolute(model.mesh_path)).generic_string();
    }
    infos[model.obj_id] = info;
    names[model.obj_id] = model.label.empty() ? "obj_" + std::to_string(model.obj_id) : model.label;
  }
  write_file_atomically(info_path, detail::bop_dump(infos));
  write_file_atomically(models_dir / "models_names.json", detail::bop_dump(names));
}

void BopWriter::write_camera(const Camera& camera) const {
  const fs::path path = root_ / "camera.json";
  const FieldContext context{path, ""};
  if (camera.width <= 0 || camera.height <= 0) context.fail("width and height must be positive");
  if (!(camera.depth_scale > 0)) context.fail("depth_scale must be positive");
  Json json;
  json["cx"] = finite(camera.cx(), "cx", context);
  json["cy"] = finite(camera.cy(), "cy", context);
  json["depth_scale"] = finite(camera.depth_scale, "depth_scale", context);
  json["fx"] = finite(camera.fx(), "fx", context);
  json["fy"] = finite(camera.fy(), "fy", context);
  json["height"] = camera.height;
  json["width"] = camera.width;
  write_file_atomically(path, detail::python_dumps(json));
}

void BopWriter::write_scene(const std::string& split, int scene_id,
                            const std::vector<ImageData>& images) const {
  if (split.empty() || split.find('/') != std::string::npos) {
    throw DatasetError(root_, "split name must be a plain folder name, got \"" + split + "\"");
  }
  if (scene_id < 0) throw DatasetError(root_ / split, "scene id must be >= 0");
  const fs::path dir = root_ / split / six_digits(scene_id);
  const fs::path camera_path = dir / "scene_camera.json";
  const fs::path gt_path = dir / "scene_gt.json";
  const fs::path graph_path = dir / "scene_graph.json";

  std::map<int, Json> cameras;
  std::map<int, Json> gts;
  std::map<int, Json> graphs;
  for (const ImageData& image : images) {
    const std::string where = location(scene_id, image.im_id);
    if (image.im_id < 0) throw DatasetError(camera_path, where + "image id must be >= 0");
    if (cameras.count(image.im_id) > 0) {
      throw DatasetError(camera_path, where + "image id appears twice");
    }
    const FieldContext camera_context{camera_path, where};
    const Camera& camera = image.camera;
    if (!(camera.depth_scale > 0)) camera_context.fail("depth_scale must be positive");
    Json entry;
    entry["cam_K"] = row_major(camera.K, "cam_K", camera_context);
    entry["depth_scale"] = finite(camera.depth_scale, "depth_scale", camera_context);
    if (camera.world_to_camera) {
      entry["cam_R_w2c"] = row_major(camera.world_to_camera->linear(), "cam_R_w2c", camera_context);
      entry["cam_t_w2c"] =
          millimetres(camera.world_to_camera->translation(), "cam_t_w2c", camera_context);
    }
    cameras[image.im_id] = entry;

    Json instances = Json::array();
    for (size_t k = 0; k < image.objects.size(); ++k) {
      const GtInstance& object = image.objects[k];
      const FieldContext context{gt_path, location(scene_id, image.im_id, static_cast<int>(k))};
      Json instance;
      instance["cam_R_m2c"] = row_major(object.model_to_camera.linear(), "cam_R_m2c", context);
      instance["cam_t_m2c"] =
          millimetres(object.model_to_camera.translation(), "cam_t_m2c", context);
      instance["obj_id"] = object.obj_id;
      instances.push_back(instance);
    }
    gts[image.im_id] = instances;

    if (image.graph) {
      const int count = static_cast<int>(image.objects.size());
      const FieldContext context{graph_path, where};
      const auto check = [&](int index, const char* field) {
        if (index < 0 || index >= count) {
          context.fail(std::string(field) + " has instance index " + std::to_string(index) +
                       " outside the image's " + std::to_string(count) + " instances");
        }
      };
      for (const auto& [parent, child] : image.graph->support) {
        check(parent, "support");
        check(child, "support");
      }
      for (const auto& [a, b] : image.graph->non_contact) {
        check(a, "non_contact");
        check(b, "non_contact");
      }
      for (const int index : image.graph->fixed) check(index, "fixed");
      Json graph;
      graph["support"] = index_pairs(image.graph->support);
      graph["non_contact"] = index_pairs(image.graph->non_contact);
      graph["fixed"] = image.graph->fixed;
      graphs[image.im_id] = graph;
    }
  }

  // Images first, then the JSON that lists them: a reader never sees an image id whose files
  // are not there yet.
  for (const ImageData& image : images) {
    if (!image.depth_m.empty()) {
      write_depth_png(dir / "depth" / (six_digits(image.im_id) + ".png"), image.depth_m,
                      image.camera.depth_scale);
    }
    if (!image.rgb.empty()) {
      const fs::path path = dir / "rgb" / (six_digits(image.im_id) + ".png");
      if (image.rgb.type() != CV_8UC3) {
        throw DatasetError(path, location(scene_id, image.im_id) + "rgb must be CV_8UC3 (BGR)");
      }
      const std::vector<unsigned char> bytes = encode_png(image.rgb, path);
      write_file_atomically(path, std::string(bytes.begin(), bytes.end()));
    }
  }
  if (!graphs.empty()) write_file_atomically(graph_path, detail::bop_dump(graphs));
  write_file_atomically(gt_path, detail::bop_dump(gts));
  write_file_atomically(camera_path, detail::bop_dump(cameras));

  std::error_code error;
  if (!images.empty() && !fs::exists(root_ / "camera.json", error)) {
    write_camera(images.front().camera);
  }
}

void write_box_ply(const fs::path& path, const Eigen::Vector3d& size_m) {
  if (!size_m.allFinite() || (size_m.array() <= 0).any()) {
    throw DatasetError(path, "box size must be positive and finite");
  }
  const Eigen::Vector3d half_mm = size_m * 500.0;
  std::ostringstream ply;
  ply.precision(17);
  ply << "ply\nformat ascii 1.0\ncomment clutterscope box, millimetres\n"
      << "element vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
      << "element face 12\nproperty list uchar int vertex_indices\nend_header\n";
  // Vertex i has x = +half if bit 0 is set, y if bit 1, z if bit 2.
  for (int i = 0; i < 8; ++i) {
    ply << ((i & 1) ? half_mm.x() : -half_mm.x()) << " " << ((i & 2) ? half_mm.y() : -half_mm.y())
        << " " << ((i & 4) ? half_mm.z() : -half_mm.z()) << "\n";
  }
  // Counter-clockwise seen from outside.
  static const int kFaces[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},   // -z, +z
                                    {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},   // -y, +y
                                    {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};  // -x, +x
  for (const auto& face : kFaces)
    ply << "3 " << face[0] << " " << face[1] << " " << face[2] << "\n";
  write_file_atomically(path, ply.str());
}

ModelInfo box_model_info(int obj_id, const Eigen::Vector3d& size_m, const fs::path& mesh_path,
                         std::string label) {
  ModelInfo model;
  model.obj_id = obj_id;
  model.label = label.empty() ? "obj_" + std::to_string(obj_id) : std::move(label);
  model.mesh_path = mesh_path;
  model.size = size_m;
  model.min = -size_m / 2;
  model.diameter = size_m.norm();
  return model;
}

}  // namespace clutterscope::datasets
