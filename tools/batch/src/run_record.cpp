#include <clutterscope/batch/build_info.hpp>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/run_record.hpp>
#include <clutterscope/datasets/files.hpp>
#include <nlohmann/json.hpp>

namespace clutterscope::batch {

void record_renderer(const std::filesystem::path& out_dir, const std::string& renderer) {
  const std::filesystem::path path = out_dir / "run.json";
  nlohmann::json run = datasets::read_json(path);
  run["gl_renderer"] = renderer.empty() ? nlohmann::json(nullptr) : nlohmann::json(renderer);
  run.update(build_record());
  write_json_atomically(path, run);
}

}  // namespace clutterscope::batch
