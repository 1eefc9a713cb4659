// `clutterscope visibility` on a copy of the tray6 sample with one model replaced by a malformed
// file (built here from the valid model): exit 3 within seconds naming the file, and under
// --keep-going the images without that model complete (exit 1). Before the hardened PLY reader
// these segfaulted, hung, or aborted the whole batch inside assimp.

#include <gtest/gtest.h>

#include <chrono>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/render/context.hpp>
#include <nlohmann/json.hpp>
#include <sstream>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "requirements.hpp"

namespace clutterscope::visibility {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::read_text;
using clutterscope::testing::run_clutterscope;
using clutterscope::testing::ScratchDir;
using clutterscope::testing::write_text;

// obj_id 7 appears only in scene 3, image 0 of tray6's six images.
constexpr const char* kModel = "models/obj_000007.ply";

// The model as an ASCII PLY (millimetres); non-empty `bad_vertex` replaces y of vertex 12,
// `bad_face` the second index of face 12.
std::string ascii_model(const fs::path& binary, const std::string& bad_vertex,
                        const std::string& bad_face) {
  const datasets::Mesh mesh = datasets::load_mesh(binary, {1.0});
  std::ostringstream text;
  text << "ply\nformat ascii 1.0\nelement vertex " << mesh.positions.size()
       << "\nproperty float x\nproperty float y\nproperty float z\nelement face "
       << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  text.precision(9);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const auto& p = mesh.positions[v];
    if (v == 12 && !bad_vertex.empty()) {
      text << p.x() << " " << bad_vertex << " " << p.z() << "\n";
    } else {
      text << p.x() << " " << p.y() << " " << p.z() << "\n";
    }
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& f = mesh.triangles[t];
    if (t == 12 && !bad_face.empty()) {
      text << "3 " << f[0] << " " << bad_face << " " << f[2] << "\n";
    } else {
      text << "3 " << f[0] << " " << f[1] << " " << f[2] << "\n";
    }
  }
  return text.str();
}

struct Case {
  std::string name;
  std::string model;    // the bytes of the malformed obj_000007.ply
  std::string message;  // part of the error
};

class MalformedModelCli : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  }
  ScratchDir scratch_{"clutterscope_malformed_model"};
};

TEST_F(MalformedModelCli, ExitsThreeNamingTheFileAndKeepGoingCompletesTheOtherImages) {
  const fs::path sample = fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray6";
  const std::string valid = read_text(sample / kModel);
  const std::size_t body = valid.find("end_header\n") + 11;
  ASSERT_GT(body, 11u);
  std::string huge_counts = valid;
  huge_counts.replace(huge_counts.find("element vertex 802"), 18, "element vertex 80200000");
  const std::vector<Case> cases = {
      {"binary body truncated among the faces", valid.substr(0, valid.size() - 10),
       "face 799: list vertex_indices of 3 items is longer than the rest of the file"},
      {"binary body truncated among the vertices", valid.substr(0, body + 5000),
       "header: element vertex 802 needs 19248 bytes, file body has 5000 bytes"},
      {"header truncated", valid.substr(0, body - 8), "file ends inside the header"},
      {"ascii face index out of range", ascii_model(sample / kModel, "", "9001"),
       "face 12: vertex index 9001 out of range (802 vertices)"},
      {"NaN coordinate", ascii_model(sample / kModel, "nan", ""),
       "vertex 12: coordinate y is not finite"},
      {"header counts larger than the file", huge_counts,
       "header: element vertex 80200000 needs 1924800000 bytes"},
  };
  for (std::size_t c = 0; c < cases.size(); ++c) {
    SCOPED_TRACE(cases[c].name);
    const fs::path data = scratch_.path() / ("data" + std::to_string(c));
    fs::copy(sample, data, fs::copy_options::recursive);
    write_text(data / kModel, cases[c].model);

    const auto start = std::chrono::steady_clock::now();
    const CommandRun run =
        run_clutterscope("visibility " + quoted(data) + " -q --out " + quoted(data / "out"));
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(30));
    EXPECT_FALSE(run.signalled);
    EXPECT_EQ(run.exit_code, 3) << run.errors;
    EXPECT_NE(run.errors.find((data / kModel).string()), std::string::npos) << run.errors;
    EXPECT_NE(run.errors.find(cases[c].message), std::string::npos) << run.errors;

    const fs::path kept = data / "kept";
    const CommandRun keep = run_clutterscope("visibility " + quoted(data) +
                                             " -q --keep-going --jobs 2 --out " + quoted(kept));
    EXPECT_FALSE(keep.signalled);
    EXPECT_EQ(keep.exit_code, 1) << keep.errors;
    const nlohmann::json summary = nlohmann::json::parse(read_text(kept / "summary.json"));
    EXPECT_EQ(summary["counts"]["items"], 6);
    EXPECT_EQ(summary["counts"]["ok"], 5);
    ASSERT_EQ(summary["counts"]["failed"], 1);
    const nlohmann::json& failure = summary["counts"]["failures"][0];
    EXPECT_EQ(failure["scene_id"], 3);
    EXPECT_EQ(failure["im_id"], 0);
    EXPECT_NE(failure["error"].get<std::string>().find(cases[c].message), std::string::npos)
        << failure.dump();
    // The other five images have their rows.
    const std::string images = read_text(kept / "images.csv");
    for (const int scene : {0, 1, 2, 4, 5}) {
      EXPECT_NE(images.find("\ntest," + std::to_string(scene) + ",0,"), std::string::npos)
          << "scene " << scene << "\n"
          << images;
    }
    EXPECT_EQ(images.find("\ntest,3,0,"), std::string::npos) << images;
  }
}

}  // namespace
}  // namespace clutterscope::visibility
