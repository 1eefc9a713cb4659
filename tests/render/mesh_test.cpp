#include <gtest/gtest.h>
#include <unistd.h>

#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/render/mesh.hpp>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace clutterscope::render {
namespace {

namespace fs = std::filesystem;

class MeshFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("clutterscope_mesh_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& contents) const {
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << contents;
    return path;
  }
  fs::path dir_;
};

// Two triangles forming a 100 mm x 50 mm rectangle at z = 20 mm, in BOP's ASCII PLY form.
constexpr const char* kAsciiPly = R"(ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
element face 2
property list uchar int vertex_indices
end_header
0 0 20
100 0 20
100 50 20
0 50 20
3 0 1 2
3 0 2 3
)";

TEST_F(MeshFiles, AsciiPlyInMillimetresLoadsInMetres) {
  const Mesh mesh = load_mesh(write("model.ply", kAsciiPly));
  EXPECT_EQ(mesh.triangle_count(), 2u);
  const Eigen::AlignedBox3f box = mesh.bounds();
  EXPECT_NEAR(box.min().x(), 0.0, 1e-9);
  EXPECT_NEAR(box.max().x(), 0.100, 1e-7);
  EXPECT_NEAR(box.max().y(), 0.050, 1e-7);
  EXPECT_NEAR(box.min().z(), 0.020, 1e-7);
  EXPECT_NEAR(box.max().z(), 0.020, 1e-7);
}

TEST_F(MeshFiles, ScaleToMetresIsApplied) {
  MeshLoadOptions options;
  options.scale_to_metres = 1.0;
  const Mesh mesh = load_mesh(write("model.ply", kAsciiPly), options);
  EXPECT_NEAR(mesh.bounds().max().x(), 100.0, 1e-5);
}

TEST_F(MeshFiles, ObjQuadsAreTriangulated) {
  const fs::path path = write("cube.obj",
                              "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                              "v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                              "f 1 2 3 4\nf 5 6 7 8\nf 1 2 6 5\n");
  MeshLoadOptions options;
  options.scale_to_metres = 0.5;
  const Mesh mesh = load_mesh(path, options);
  EXPECT_EQ(mesh.triangle_count(), 6u);
  EXPECT_NEAR(mesh.bounds().max().z(), 0.5, 1e-7);
  EXPECT_EQ(mesh.normals.size(), mesh.positions.size());
}

TEST_F(MeshFiles, AsciiStlLoads) {
  const fs::path path = write("tri.stl",
                              "solid t\n"
                              "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 10 0 0\n"
                              "vertex 0 10 0\nendloop\nendfacet\n"
                              "facet normal 0 0 1\nouter loop\nvertex 10 0 0\nvertex 10 10 0\n"
                              "vertex 0 10 0\nendloop\nendfacet\n"
                              "endsolid t\n");
  const Mesh mesh = load_mesh(path);
  EXPECT_EQ(mesh.triangle_count(), 2u);
  EXPECT_NEAR(mesh.bounds().max().y(), 0.010, 1e-8);
}

std::string base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t chunk =
        (static_cast<std::uint8_t>(bytes[i]) << 16) |
        (i + 1 < bytes.size() ? static_cast<std::uint8_t>(bytes[i + 1]) << 8 : 0) |
        (i + 2 < bytes.size() ? static_cast<std::uint8_t>(bytes[i + 2]) : 0);
    out += table[(chunk >> 18) & 63];
    out += table[(chunk >> 12) & 63];
    out += i + 1 < bytes.size() ? table[(chunk >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? table[chunk & 63] : '=';
  }
  return out;
}

TEST_F(MeshFiles, GltfWithEmbeddedBufferLoads) {
  const float positions[9] = {0, 0, 0, 2, 0, 0, 0, 3, 0};  // metres in glTF
  const std::uint16_t indices[4] = {0, 1, 2, 0};           // padded to 4-byte multiple
  std::string buffer(sizeof(positions) + sizeof(indices), '\0');
  std::memcpy(buffer.data(), positions, sizeof(positions));
  std::memcpy(buffer.data() + sizeof(positions), indices, sizeof(indices));
  const std::string gltf = R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
"buffers":[{"byteLength":)" +
                           std::to_string(buffer.size()) +
                           R"(,"uri":"data:application/octet-stream;base64,)" + base64(buffer) +
                           R"("}],
"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},
               {"buffer":0,"byteOffset":36,"byteLength":6}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
              "min":[0,0,0],"max":[2,3,0]},
             {"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}]})";
  MeshLoadOptions options;
  options.scale_to_metres = 1.0;
  const Mesh mesh = load_mesh(write("tri.gltf", gltf), options);
  EXPECT_EQ(mesh.triangle_count(), 1u);
  EXPECT_NEAR(mesh.bounds().max().y(), 3.0, 1e-6);
}

TEST_F(MeshFiles, MissingFileIsDatasetErrorNamingIt) {
  const fs::path path = dir_ / "obj_000007.ply";
  try {
    load_mesh(path);
    FAIL() << "no exception";
  } catch (const datasets::DatasetError& error) {
    EXPECT_EQ(error.file(), path);
    EXPECT_NE(std::string(error.what()).find("obj_000007.ply"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("not found"), std::string::npos);
  }
}

TEST_F(MeshFiles, EmptyFileIsDatasetError) {
  const fs::path path = write("empty.ply", "");
  try {
    load_mesh(path);
    FAIL() << "no exception";
  } catch (const datasets::DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("empty"), std::string::npos) << error.what();
  }
}

TEST_F(MeshFiles, GarbageFileIsDatasetError) {
  EXPECT_THROW(load_mesh(write("garbage.ply", "this is not a mesh\n\x01\x02")),
               datasets::DatasetError);
}

TEST_F(MeshFiles, PointCloudWithoutFacesIsDatasetError) {
  const fs::path path =
      write("points.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
            "property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_THROW(load_mesh(path), datasets::DatasetError);
}

TEST_F(MeshFiles, WritePlyRoundTripsInMillimetresWithBopHeader) {
  const Mesh box = box_mesh(Eigen::Vector3f(0.1f, 0.2f, 0.3f), 2);
  const fs::path path = dir_ / "obj_000001.ply";
  write_ply(path, box);

  std::ifstream file(path, std::ios::binary);
  const std::string contents((std::istreambuf_iterator<char>(file)), {});
  const std::string header = contents.substr(0, contents.find("end_header\n"));
  EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(header.find("element vertex " + std::to_string(box.positions.size())),
            std::string::npos);
  EXPECT_NE(header.find("property float nx\nproperty float ny\nproperty float nz"),
            std::string::npos);
  EXPECT_NE(header.find("property list uchar int vertex_indices"), std::string::npos);
  // First vertex x in the file is in millimetres.
  float first_x = 0;
  std::memcpy(&first_x, contents.data() + contents.find("end_header\n") + 11, sizeof(float));
  EXPECT_FLOAT_EQ(first_x, box.positions[0].x() * 1000.0f);

  const Mesh loaded = load_mesh(path);  // default: mm -> m
  ASSERT_EQ(loaded.triangle_count(), box.triangle_count());
  ASSERT_EQ(loaded.positions.size(), box.positions.size());
  for (std::size_t v = 0; v < box.positions.size(); ++v) {
    EXPECT_LT((loaded.positions[v] - box.positions[v]).norm(), 1e-7f);
    EXPECT_LT((loaded.normals[v] - box.normals[v]).norm(), 1e-6f);
  }
  for (std::size_t t = 0; t < box.triangles.size(); ++t) {
    EXPECT_EQ(loaded.triangles[t], box.triangles[t]);
  }
}

TEST(BoxMesh, TriangleCountAndExtents) {
  const Mesh box = box_mesh(Eigen::Vector3f(0.1f, 0.2f, 0.3f), 13);
  EXPECT_EQ(box.triangle_count(), 12u * 13 * 13);
  EXPECT_TRUE(box.bounds().min().isApprox(Eigen::Vector3f(-0.05f, -0.1f, -0.15f)));
  EXPECT_TRUE(box.bounds().max().isApprox(Eigen::Vector3f(0.05f, 0.1f, 0.15f)));
  // Every triangle's winding agrees with its outward normal.
  for (const auto& t : box.triangles) {
    const Eigen::Vector3f n = (box.positions[t[1]] - box.positions[t[0]])
                                  .cross(box.positions[t[2]] - box.positions[t[0]]);
    EXPECT_GT(n.dot(box.normals[t[0]]), 0);
  }
}

// Distance from p to the surface of the axis-aligned box [-h, h].
float distance_to_box_surface(const Eigen::Vector3f& p, const Eigen::Vector3f& h) {
  const Eigen::Vector3f q = p.cwiseAbs() - h;
  const float outside = q.cwiseMax(0.0f).norm();
  const float inside = std::min(q.maxCoeff(), 0.0f);
  return std::abs(outside + inside);
}

TEST(Decimate, ReducesToBudgetAndStaysOnTheSurface) {
  const Eigen::Vector3f size(0.1f, 0.06f, 0.04f);
  const Mesh dense = box_mesh(size, 40);  // 19200 triangles
  const Mesh proxy = decimate(dense, 1500);
  EXPECT_LE(proxy.triangle_count(), 1500u);
  EXPECT_GE(proxy.triangle_count(), 300u);  // not collapsed to a handful
  EXPECT_EQ(proxy.normals.size(), proxy.positions.size());
  // Cluster means of surface points stay within one grid cell of the surface, and the bounds
  // shrink by less than a cell. The finest grid within budget has cells well under 1 cm here.
  const float cell = 0.01f;
  for (const auto& p : proxy.positions) {
    EXPECT_LT(distance_to_box_surface(p, size / 2), cell);
  }
  EXPECT_LT((proxy.bounds().max() - dense.bounds().max()).cwiseAbs().maxCoeff(), cell);
  EXPECT_LT((proxy.bounds().min() - dense.bounds().min()).cwiseAbs().maxCoeff(), cell);
  for (const auto& t : proxy.triangles) {
    EXPECT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
    for (const auto index : t) EXPECT_LT(index, proxy.positions.size());
  }
}

TEST(Decimate, SmallMeshIsReturnedUnchanged) {
  const Mesh box = box_mesh(Eigen::Vector3f(1, 1, 1), 2);
  const Mesh same = decimate(box, 1000);
  EXPECT_EQ(same.triangle_count(), box.triangle_count());
  EXPECT_EQ(same.positions, box.positions);
}

TEST(Decimate, RejectsTinyBudget) {
  EXPECT_THROW(decimate(box_mesh({1, 1, 1}), 2), std::invalid_argument);
}

}  // namespace
}  // namespace clutterscope::render
