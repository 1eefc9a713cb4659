#include "fuzz_support.hpp"

#include <unistd.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/visibility/bop_visibility.hpp>
#include <fstream>
#include <stdexcept>

namespace clutterscope::fuzz {

namespace fs = std::filesystem;

namespace {

class ScratchDir {
 public:
  ScratchDir() {
    std::error_code error;
    const fs::path base =
        fs::is_directory("/dev/shm", error) ? fs::path("/dev/shm") : fs::temp_directory_path();
    path_ = base / ("clutterscope-fuzz-" + std::to_string(::getpid()));
    fs::remove_all(path_, error);
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code error;
    fs::remove_all(path_, error);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

void write_text(const fs::path& path, const std::string& text) {
  write_bytes(path, reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

std::string base_models_info() {
  std::string text = "{\n";
  for (int id = 1; id <= 16; ++id) {
    text += "  \"" + std::to_string(id) +
            "\": {\"diameter\": 173.2, \"min_x\": -50.0, \"min_y\": -50.0, \"min_z\": -50.0, "
            "\"size_x\": 100.0, \"size_y\": 100.0, \"size_z\": 100.0}";
    text += id < 16 ? ",\n" : "\n";
  }
  return text + "}";
}

// The 100 mm cube centred on the origin that base_models_info() describes.
std::string box_ply_100mm() {
  std::string text =
      "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
      "property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < 8; ++i) {
    text += std::string((i & 1) ? "50" : "-50") + ((i & 2) ? " 50" : " -50") +
            ((i & 4) ? " 50\n" : " -50\n");
  }
  return text +
         "3 0 2 3\n3 0 3 1\n3 4 5 7\n3 4 7 6\n3 0 1 5\n3 0 5 4\n"
         "3 2 6 7\n3 2 7 3\n3 0 4 6\n3 0 6 2\n3 1 3 7\n3 1 7 5\n";
}

std::string base_scene_gt() {
  std::string text = "{\n  \"0\": [";
  for (int k = 0; k < 10; ++k) {
    text += std::string(k ? ", " : "") +
            "{\"cam_R_m2c\": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], \"cam_t_m2c\": [" +
            std::to_string(40 * k - 180) + ".0, 0.0, 900.0], \"obj_id\": " + std::to_string(k + 1) +
            "}";
  }
  return text + "]\n}";
}

// The dataset every run starts from, written once per process.
const fs::path& base_dataset() {
  static const fs::path root = [] {
    const fs::path dir = scratch_dir() / "dataset";
    const fs::path models = dir / "models";
    const fs::path scene = dir / "test" / "000000";
    fs::create_directories(models);
    fs::create_directories(scene);
    write_text(models / "models_info.json", base_models_info());
    std::string names = "{";
    for (int id = 1; id <= 16; ++id) {
      char file[32];
      std::snprintf(file, sizeof(file), "obj_%06d.ply", id);
      write_text(models / file, box_ply_100mm());  // load() checks it against models_info
      names += std::string(id > 1 ? ", " : "") + "\"" + std::to_string(id) + "\": \"object " +
               std::to_string(id) + "\"";
    }
    write_text(models / "models_names.json", names + "}");
    write_text(dir / "camera.json",
               "{\"cx\": 320.0, \"cy\": 240.0, \"depth_scale\": 0.1, \"fx\": 525.0, "
               "\"fy\": 525.0, \"height\": 480, \"width\": 640}");
    write_text(scene / "scene_camera.json",
               "{\n  \"0\": {\"cam_K\": [525.0, 0.0, 320.0, 0.0, 525.0, 240.0, 0.0, 0.0, 1.0], "
               "\"depth_scale\": 0.1}\n}");
    write_text(scene / "scene_gt.json", base_scene_gt());
    write_text(scene / "scene_graph.json",
               "{\n  \"0\": {\"fixed\": [0], \"non_contact\": [[2, 4]], \"support\": [[0, 1], "
               "[1, 2], [1, 3]]}\n}");
    return dir;
  }();
  return root;
}

void use_dataset(const fs::path& root, const DatasetUse& use) {
  std::optional<datasets::BopDataset> dataset;
  std::vector<datasets::ImageKey> keys;
  try {
    dataset = datasets::BopDataset::open(root);
    if (!use.detections.empty()) dataset->attach_detections(root / use.detections);
    if (!use.targets.empty()) {
      dataset->attach_targets(datasets::read_test_targets(root / use.targets), root / use.targets);
    }
    keys = dataset->list_images(datasets::DatasetSelection{});
  } catch (const datasets::DatasetError&) {
    return;
  }
  for (const auto& key : keys) {
    try {
      const datasets::SceneView view = dataset->load(key);
      if (!use.decode_depth) continue;
      const cv::Mat metres = datasets::load_depth(view);
      const cv::Mat millimetres =
          visibility::load_bop_depth_mm(view.depth_path.string(), view.camera.depth_scale,
                                        view.camera.width, view.camera.height, "");
      if (metres.size() != millimetres.size()) throw std::logic_error("depth sizes differ");
    } catch (const datasets::DatasetError&) {
    }
  }
}

}  // namespace

const fs::path& scratch_dir() {
  static const ScratchDir dir;
  return dir.path();
}

void write_bytes(const fs::path& path, const std::uint8_t* data, std::size_t size) {
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  stream.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!stream) throw std::runtime_error("fuzz: cannot write " + path.string());
}

void run_dataset_with(const fs::path& relative_file, const std::uint8_t* data, std::size_t size,
                      const DatasetUse& use) {
  // A process fuzzes one file: each run replaces the previous run's input, the rest stays.
  const fs::path& root = base_dataset();
  const fs::path file = root / relative_file;
  fs::create_directories(file.parent_path());
  write_bytes(file, data, size);
  use_dataset(root, use);
}

}  // namespace clutterscope::fuzz
