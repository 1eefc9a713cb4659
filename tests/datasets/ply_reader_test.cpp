#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <chrono>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

// The hardened PLY reader behind load_mesh: hand-written small files with known results, the
// malformed files that crashed or hung assimp, and agreement with assimp on valid files.

#include "datasets/mesh_file_fixture.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;

class PlyFiles : public MeshFileTest {
 protected:
  // The message of the DatasetError that loading `contents` throws ("" if none).
  std::string error_of(const std::string& contents) const {
    const fs::path path = write("bad.ply", contents);
    try {
      load_mesh(path, {1.0});
    } catch (const DatasetError& error) {
      EXPECT_EQ(error.file(), path);
      return error.what();
    }
    ADD_FAILURE() << "no DatasetError";
    return "";
  }
};

// Binary records written in either byte order.
class Bytes {
 public:
  explicit Bytes(bool big_endian) : big_endian_(big_endian) {}
  template <typename T>
  Bytes& put(T value) {
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    if (big_endian_) std::reverse(raw, raw + sizeof(T));
    data_.append(raw, sizeof(T));
    return *this;
  }
  const std::string& str() const { return data_; }

 private:
  bool big_endian_;
  std::string data_;
};

using Triangle = std::array<std::uint32_t, 3>;

// A unit square (a quad) and a triangle beside it; vertices carry colours, the face element
// texture coordinates, and an extra element follows. In ascii.
constexpr const char* kAsciiQuad = R"(ply
format ascii 1.0
comment made by hand
obj_info extra properties everywhere
element vertex 5
property float x
property uchar red
property float y
property float z
property uchar green
property uchar blue
element face 2
property list uchar int vertex_indices
property list uchar float texcoord
element material 1
property float shininess
end_header
0 255 0 0 0 0
1 0 0 0 1 2
1 3 1 0 4 5
0 6 1 0 7 8
2 9 0 +1e0 10 11
4 0 1 2 3 8 0 0 1 0 1 1 0 1
3 1 4 2 0
0.5
)";

TEST_F(PlyFiles, AsciiQuadWithExtraPropertiesAndElements) {
  const Mesh mesh = load_mesh(write("quad.ply", kAsciiQuad), {1.0});
  const std::vector<Eigen::Vector3f> positions = {
      {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 1}};
  EXPECT_EQ(mesh.positions, positions);
  // The quad is fanned from its first corner; the triangle after it starts with that corner's
  // successor, so it stays as it is.
  const std::vector<Triangle> triangles = {{0, 1, 2}, {0, 2, 3}, {1, 4, 2}};
  EXPECT_EQ(mesh.triangles, triangles);
  ASSERT_EQ(mesh.normals.size(), 5u);  // generated, as assimp does
  EXPECT_TRUE(mesh.normals[3].isApprox(Eigen::Vector3f(0, 0, 1))) << mesh.normals[3];
}

std::string binary_model(bool big_endian) {
  // Double coordinates with normals and an int16 property to skip; ushort counts, uint
  // indices; one quad, one triangle.
  std::string header = std::string("ply\nformat ") +
                       (big_endian ? "binary_big_endian" : "binary_little_endian") +
                       " 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
                       "property double z\nproperty short quality\nproperty float nx\n"
                       "property float ny\nproperty float nz\nelement face 2\n"
                       "property list ushort uint vertex_indices\nend_header\n";
  Bytes body(big_endian);
  const double xyz[4][3] = {{0, 0, 0}, {10, 0, 0}, {10, 20, 0}, {0, 20, 5}};
  for (const auto& p : xyz) {
    body.put(p[0]).put(p[1]).put(p[2]).put<std::int16_t>(-7);
    body.put(0.0f).put(0.0f).put(1.0f);
  }
  body.put<std::uint16_t>(4).put<std::uint32_t>(0).put<std::uint32_t>(1).put<std::uint32_t>(2);
  body.put<std::uint32_t>(3);
  body.put<std::uint16_t>(3).put<std::uint32_t>(0).put<std::uint32_t>(2).put<std::uint32_t>(3);
  return header + body.str();
}

TEST_F(PlyFiles, BinaryBothByteOrdersWithNormalsAndSkippedProperty) {
  for (const bool big_endian : {false, true}) {
    SCOPED_TRACE(big_endian ? "big endian" : "little endian");
    const Mesh mesh = load_mesh(write("model.ply", binary_model(big_endian)));  // mm -> m
    ASSERT_EQ(mesh.positions.size(), 4u);
    EXPECT_EQ(mesh.positions[2], Eigen::Vector3f(10 * 0.001f, 20 * 0.001f, 0));
    EXPECT_EQ(mesh.positions[3], Eigen::Vector3f(0, 20 * 0.001f, 5 * 0.001f));
    // The triangle after the quad starts with the quad's fan corner: assimp's NGON encoding
    // rotates it to (3, 0, 2).
    const std::vector<Triangle> triangles = {{0, 1, 2}, {0, 2, 3}, {3, 0, 2}};
    EXPECT_EQ(mesh.triangles, triangles);
    ASSERT_EQ(mesh.normals.size(), 4u);
    EXPECT_EQ(mesh.normals[1], Eigen::Vector3f(0, 0, 1));
  }
}

TEST_F(PlyFiles, ConcaveQuadIsFannedFromItsConcaveCorner) {
  // An arrow head: corner 2 points inwards.
  const Mesh mesh = load_mesh(write("arrow.ply",
                                    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                                    "property float y\nproperty float z\nelement face 1\n"
                                    "property list uchar int vertex_indices\nend_header\n"
                                    "0 0 0\n2 1 0\n0 2 0\n0.5 1 0\n4 0 1 2 3\n"),
                              {1.0});
  const std::vector<Triangle> triangles = {{3, 0, 1}, {3, 1, 2}};
  EXPECT_EQ(mesh.triangles, triangles);
}

TEST_F(PlyFiles, LinesAreDroppedAndTriangleCornersCopied) {
  // As assimp's SortByPType: a file with lines and triangles keeps the triangles, each corner
  // its own vertex.
  const Mesh mesh = load_mesh(write("lines.ply",
                                    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                                    "property float y\nproperty float z\nelement face 2\n"
                                    "property list uchar int vertex_indices\nend_header\n"
                                    "0 0 0\n1 0 0\n0 1 0\n5 5 5\n3 2 0 1\n2 1 3\n"),
                              {1.0});
  const std::vector<Eigen::Vector3f> positions = {{0, 1, 0}, {0, 0, 0}, {1, 0, 0}};
  EXPECT_EQ(mesh.positions, positions);
  const std::vector<Triangle> triangles = {{0, 1, 2}};
  EXPECT_EQ(mesh.triangles, triangles);
}

TEST_F(PlyFiles, ConvexPentagonIsFannedAndConcaveRefused) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const Mesh mesh = load_mesh(
      write("pentagon.ply", header + "0 0 0\n2 0 0\n3 1 0\n1 2 0\n-1 1 0\n5 0 1 2 3 4\n"));
  const std::vector<Triangle> triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}};
  EXPECT_EQ(mesh.triangles, triangles);
  const std::string message =
      error_of(header + "0 0 0\n2 0 0\n1 0.2 0\n1 2 0\n-1 1 0\n5 0 1 2 3 4\n");
  EXPECT_NE(message.find("face 0: concave polygon of 5 vertices"), std::string::npos) << message;
}

// --- malformed files -------------------------------------------------------------------------

std::string sample_model() {
  std::ifstream file(fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray6" / "models" / "obj_000001.ply",
                     std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(file), {});
}

TEST_F(PlyFiles, BinaryBodyTruncatedIsRefusedNamingTheRecord) {
  const std::string valid = sample_model();
  ASSERT_GT(valid.size(), 1000u);
  // Header counts are checked first: a body cut short of the fixed-size vertices is refused
  // by the header check.
  std::string message = error_of(valid.substr(0, valid.find("end_header\n") + 11 + 100));
  EXPECT_NE(message.find("header: element vertex 802 needs 19248 bytes, file body has 100 bytes"),
            std::string::npos)
      << message;
  // A cut among the faces (variable-size lists) is found reading them.
  message = error_of(valid.substr(0, valid.size() - 7));
  EXPECT_NE(message.find("face 799: list vertex_indices of 3 items is longer than the rest of "
                         "the file (5 bytes)"),
            std::string::npos)
      << message;
  // An ascii file cut before its last record.
  const std::string ascii = kAsciiQuad;
  message = error_of(ascii.substr(0, ascii.find("0.5\n")));
  EXPECT_NE(message.find("material 0: file ends inside the record (property shininess)"),
            std::string::npos)
      << message;
}

TEST_F(PlyFiles, HeaderTruncatedIsRefusedAtOnce) {
  const std::string valid = sample_model();
  for (const std::size_t cut : {std::size_t{5}, std::size_t{60}, valid.find("end_header") + 4}) {
    const auto start = std::chrono::steady_clock::now();
    const std::string message = error_of(valid.substr(0, cut));
    EXPECT_NE(message.find("header: file ends inside the header"), std::string::npos) << message;
    // A hang guard, not a timing: assimp hung for ever on these files.
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(30));
  }
}

TEST_F(PlyFiles, IndexOutOfRangeIsRefused) {
  std::string ply = kAsciiQuad;
  ply.replace(ply.find("3 1 4 2 0"), 9, "3 1 9001 2 0");
  std::string message = error_of(ply);
  EXPECT_NE(message.find("face 1: vertex index 9001 out of range (5 vertices)"), std::string::npos)
      << message;
  ply = kAsciiQuad;
  ply.replace(ply.find("3 1 4 2 0"), 9, "3 1 -1 2 0");
  message = error_of(ply);
  EXPECT_NE(message.find("face 1: vertex index -1 out of range"), std::string::npos) << message;
}

TEST_F(PlyFiles, NonFiniteCoordinateIsRefused) {
  for (const char* bad : {"nan", "inf", "-inf", "1e999"}) {
    std::string ply = kAsciiQuad;
    ply.replace(ply.find("1 3 1 0"), 7, std::string("1 3 ") + bad + " 0");
    const std::string message = error_of(ply);
    EXPECT_NE(message.find("vertex 2: coordinate y is not finite"), std::string::npos)
        << bad << ": " << message;
  }
  // And in binary: a NaN float in the sample's vertex 5.
  std::string valid = sample_model();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(valid.data() + valid.find("end_header\n") + 11 + 5 * 24 + 8, &nan, 4);
  const std::string message = error_of(valid);
  EXPECT_NE(message.find("vertex 5: coordinate z is not finite"), std::string::npos) << message;
}

TEST_F(PlyFiles, CountsLargerThanTheFileAreRefusedBeforeAllocating) {
  std::string valid = sample_model();
  valid.replace(valid.find("element vertex 802"), 18, "element vertex 1000000000000");
  std::string message = error_of(valid);
  EXPECT_NE(message.find("header: element vertex 1000000000000 needs 24000000000000 bytes"),
            std::string::npos)
      << message;
  std::string ply = kAsciiQuad;
  ply.replace(ply.find("element face 2"), 14, "element face 18446744073709551615");
  message = error_of(ply);
  EXPECT_NE(message.find("header: element face 18446744073709551615 needs at least"),
            std::string::npos)
      << message;
  // A list longer than the rest of the file.
  ply = kAsciiQuad;
  ply.replace(ply.find("3 1 4 2 0"), 9, "255 1 4 2 0");
  message = error_of(ply);
  EXPECT_NE(message.find("face 1: list vertex_indices of 255 items is longer than the rest"),
            std::string::npos)
      << message;
}

TEST_F(PlyFiles, MalformedHeadersAreRefused) {
  const std::string head = "ply\nformat ascii 1.0\n";
  EXPECT_NE(
      error_of(head + std::string(5000, 'c') + "\nend_header\n").find("header line 3: longer"),
      std::string::npos);
  std::string comments;
  while (comments.size() < (1u << 20)) comments += "comment " + std::string(100, 'x') + "\n";
  EXPECT_NE(error_of(head + comments + "end_header\n").find("no end_header in the first"),
            std::string::npos);
  EXPECT_NE(error_of(head + "element vertex 3\nproperty floot x\nend_header\n")
                .find("header line 4: unknown type 'floot'"),
            std::string::npos);
  EXPECT_NE(error_of("ply\nformat binary_middle_endian 1.0\nend_header\n").find("unknown format"),
            std::string::npos);
  EXPECT_NE(
      error_of(head + "element vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n")
          .find("no scalar property z"),
      std::string::npos);
  EXPECT_NE(
      error_of(head + "element vertex -3\nend_header\n").find("is not a non-negative integer"),
      std::string::npos);
  EXPECT_NE(error_of(head + "element vertex 0\nelement edge 5\nend_header\n1 2 3 4 5\n")
                .find("element edge has 5 records but no properties"),
            std::string::npos);
  EXPECT_NE(error_of("not a ply at all\n").find("not a PLY file"), std::string::npos);
}

TEST_F(PlyFiles, AsciiGarbageNumberIsRefused) {
  std::string ply = kAsciiQuad;
  ply.replace(ply.find("1 3 1 0"), 7, "1 3 one 0");
  const std::string message = error_of(ply);
  EXPECT_NE(message.find("vertex 2: property y: 'one' is not a number"), std::string::npos)
      << message;
}

// --- agreement with assimp on valid files ----------------------------------------------------

Mesh assimp_mesh(const fs::path& path) {
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene =
      importer.ReadFile(path.string(), aiProcess_Triangulate | aiProcess_PreTransformVertices |
                                           aiProcess_SortByPType | aiProcess_GenSmoothNormals);
  EXPECT_NE(scene, nullptr) << importer.GetErrorString();
  Mesh mesh;
  if (scene == nullptr) return mesh;
  EXPECT_EQ(scene->mNumMeshes, 1u);
  const aiMesh* part = scene->mMeshes[0];
  for (unsigned v = 0; v < part->mNumVertices; ++v) {
    const aiVector3D& p = part->mVertices[v];
    mesh.positions.emplace_back(p.x * 0.001f, p.y * 0.001f, p.z * 0.001f);
    const aiVector3D& n = part->mNormals[v];
    mesh.normals.emplace_back(n.x, n.y, n.z);
  }
  for (unsigned f = 0; f < part->mNumFaces; ++f) {
    const aiFace& face = part->mFaces[f];
    mesh.triangles.push_back({face.mIndices[0], face.mIndices[1], face.mIndices[2]});
  }
  return mesh;
}

void expect_same_as_assimp(const fs::path& path, bool file_has_normals) {
  SCOPED_TRACE(path.string());
  const Mesh ours = load_mesh(path);
  const Mesh theirs = assimp_mesh(path);
  EXPECT_EQ(ours.positions, theirs.positions);
  EXPECT_EQ(ours.triangles, theirs.triangles);
  ASSERT_EQ(ours.normals.size(), theirs.normals.size());
  if (file_has_normals) {
    EXPECT_EQ(ours.normals, theirs.normals);
  } else {
    // Generated normals: assimp groups vertices within an epsilon and sums in another order.
    for (std::size_t v = 0; v < ours.normals.size(); ++v) {
      EXPECT_LT((ours.normals[v] - theirs.normals[v]).norm(), 1e-5f) << "vertex " << v;
    }
  }
}

TEST_F(PlyFiles, SameMeshAsAssimpForTheBundledModels) {
  std::vector<fs::path> models;
  for (const fs::path& dir : {fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray6" / "models",
                              fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray10" / "models",
                              fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "ycbv_real" / "models",
                              fs::path(CLUTTERSCOPE_SAMPLES_DIR) / ".." / ".." / "tests" /
                                  "visibility" / "data" / "bop_toolkit_reference" / "models"}) {
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (entry.path().extension() == ".ply") models.push_back(entry.path());
    }
  }
  EXPECT_GE(models.size(), 43u);
  for (const fs::path& model : models) expect_same_as_assimp(model, true);
}

// scripts/ply_ascii_to_binary.py (how the ycbv_real sample's models were made): the binary file
// loads to the same mesh as the ASCII one, each float32 rounded from the decimal text itself. The
// first x lies just above the midpoint of 1 and the next float, 1 + 2^-23, by less than half a
// double ulp: rounded through double it would tie to 1.
TEST_F(PlyFiles, AsciiToBinaryScriptGivesTheSameMesh) {
  const std::string header =
      "ply\nformat ascii 1.0\ncomment units: mm\nelement vertex 4\nproperty float x\n"
      "property float y\nproperty float z\nproperty float nx\nproperty float ny\n"
      "property float nz\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
  const fs::path ascii =
      write("ascii.ply", header +
                             "1.00000005960464477539062500001 -45.096000 0.1 0 0 1\n"
                             "1.0000000596046447753906249999 1.694000 -15.447 0 0 1\n"
                             "-36.058 -24.192000 3e2 -0.999044 0.043718 0.000023\n"
                             "0 1 0 -0.782937 -0.618369 -0.068047\n3 0 1 2\n4 0 1 2 3\n");
  const fs::path binary = dir_ / "binary.ply";
  const fs::path script =
      fs::path(CLUTTERSCOPE_SAMPLES_DIR) / ".." / ".." / "scripts" / "ply_ascii_to_binary.py";
  const std::string command = "python3 '" + script.string() + "' '" + ascii.string() + "' '" +
                              binary.string() + "' > '" + (dir_ / "log").string() + "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;

  std::ifstream file(binary, std::ios::binary);
  const std::string bytes(std::istreambuf_iterator<char>(file), {});
  std::string expected_header = header;
  expected_header.replace(expected_header.find("ascii"), 5, "binary_little_endian");
  ASSERT_EQ(bytes.substr(0, expected_header.size()), expected_header);
  EXPECT_EQ(bytes.size(), expected_header.size() + 4 * 6 * 4 + (1 + 3 * 4) + (1 + 4 * 4));

  const Mesh from_ascii = load_mesh(ascii, {1.0});
  const Mesh from_binary = load_mesh(binary, {1.0});
  EXPECT_EQ(from_binary.positions, from_ascii.positions);
  EXPECT_EQ(from_binary.normals, from_ascii.normals);
  EXPECT_EQ(from_binary.triangles, from_ascii.triangles);
  ASSERT_EQ(from_binary.positions.size(), 4u);
  EXPECT_EQ(from_binary.positions[0].x(), 1.0f + std::ldexp(1.0f, -23));
  EXPECT_EQ(from_binary.positions[1].x(), 1.0f);
  EXPECT_EQ(from_binary.positions[2].z(), 300.0f);
}

TEST_F(PlyFiles, SameMeshAsAssimpForPolygonsLinesAndGeneratedNormals) {
  // Quads (one concave), triangles rotated by the NGON encoding, both byte orders, no normals.
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 9\nproperty float x\nproperty float y\n"
      "property float z\nelement face 5\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n3 1 0\n2 2 0\n0 0 5\n1 0.5 5\n";
  expect_same_as_assimp(
      write("quads.ply", header + "3 0 1 2\n4 0 4 5 6\n4 1 2 3 0\n3 1 5 6\n4 0 4 2 5\n"), false);
  expect_same_as_assimp(
      write("lines.ply", header + "3 0 1 2\n2 7 8\n4 1 2 3 0\n3 1 5 6\n4 7 8 2 3\n"), false);
  expect_same_as_assimp(write("le.ply", binary_model(false)), true);
  expect_same_as_assimp(write("be.ply", binary_model(true)), true);
  std::string quad = kAsciiQuad;
  expect_same_as_assimp(write("colours.ply", quad), false);
}

}  // namespace
}  // namespace clutterscope::datasets
