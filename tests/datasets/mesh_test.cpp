#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <string>

#include "datasets/mesh_file_fixture.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;

using MeshFiles = MeshFileTest;

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

// OBJ and STL reach assimp only after checks; each refusal names the file and the line.
TEST_F(MeshFiles, MalformedObjAndStlAreRefusedBeforeAssimp) {
  const auto message_of = [&](const std::string& name, const std::string& contents) {
    try {
      load_mesh(write(name, contents));
    } catch (const DatasetError& error) {
      EXPECT_EQ(error.file(), dir_ / name);
      return std::string(error.what());
    }
    ADD_FAILURE() << name << ": no DatasetError";
    return std::string();
  };
  const std::string square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\n";
  EXPECT_NE(message_of("a.obj", square + "f 1 2 9\n")
                .find("line 6: vertex index 9 out of range (4 vertices)"),
            std::string::npos);
  EXPECT_NE(message_of("b.obj", square + "f 1 2 -5\n").find("line 6: vertex index -5 out of range"),
            std::string::npos);
  EXPECT_NE(message_of("c.obj", square + "f 1/1 2/2 3/1\n")
                .find("line 6: texture coordinate index 2 out of range (1 texture coordinates)"),
            std::string::npos);
  EXPECT_NE(message_of("d.obj", square + "f 1//3 2//1 3//1\n").find("normal index 3 out of range"),
            std::string::npos);
  EXPECT_NE(message_of("e.obj", "v 0 nan 0\n" + square + "f 1 2 3\n")
                .find("line 1: vertex coordinate 'nan' is not a finite number"),
            std::string::npos);
  EXPECT_NE(
      message_of("f.obj", square + "f 1 x 3\n").find("line 6: 'x' is not a valid face corner"),
      std::string::npos);
  EXPECT_NE(message_of("g.obj", std::string(70000, '#') + "\n").find("line 1: longer than"),
            std::string::npos);
  // Relative indices within range load.
  EXPECT_EQ(load_mesh(write("h.obj", square + "f -4 -3 -2\n")).triangle_count(), 1u);

  // Binary STL: 84 + 50 bytes per triangle, exactly.
  std::string stl(84 + 50, '\0');
  stl[80] = 1;
  EXPECT_NE(message_of("a.stl", stl.substr(0, 120))
                .find("binary STL of 120 bytes, expected 134 (84 + 50 x 1 triangles)"),
            std::string::npos);
  stl[80] = 7;
  EXPECT_NE(message_of("b.stl", stl).find("expected 434"), std::string::npos);
  EXPECT_NE(message_of("c.stl",
                       "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                       "vertex 1 0 0\nendloop\nendfacet\nendsolid t\n")
                .find("line 7: facet with 2 vertices, expected 3"),
            std::string::npos);
  EXPECT_NE(message_of("d.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 inf\n")
                .find("line 4: vertex coordinate 'inf' is not a finite number"),
            std::string::npos);
  EXPECT_NE(message_of("e.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n")
                .find("file ends inside a facet"),
            std::string::npos);
  // Found by fuzzing: assimp leaked its mesh on a facet line that strays from the grammar.
  EXPECT_NE(message_of("f.stl", "solid t\nfacet ;normal 0 0 1\nouter loop\n")
                .find("line 2: expected 'facet normal nx ny nz'"),
            std::string::npos);
  EXPECT_NE(message_of("g.stl", "solid t\nfacet normal 0 nan 1\n")
                .find("line 2: facet normal 'nan' is not a finite number"),
            std::string::npos);
  EXPECT_NE(message_of("h.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvortex 0 0 0\n")
                .find("line 4: 'vortex' is not a keyword of ASCII STL"),
            std::string::npos);
  EXPECT_NE(message_of("i.stl", "solid t\nouter loop\n").find("line 2: outer outside a facet"),
            std::string::npos);
  // Found by fuzzing: assimp reads one word of name after "solid" and a facet after it.
  EXPECT_NE(message_of("j.stl", std::string("solid box\016 facet normal 0 lid box\n"))
                .find("line 1: the solid's name is one word; 'facet' after it holds 'facet'"),
            std::string::npos);
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
  } catch (const DatasetError& error) {
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
  } catch (const DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("empty"), std::string::npos) << error.what();
  }
}

TEST_F(MeshFiles, GarbageFileIsDatasetError) {
  EXPECT_THROW(load_mesh(write("garbage.ply", "this is not a mesh\n\x01\x02")), DatasetError);
}

TEST_F(MeshFiles, PointCloudWithoutFacesIsDatasetError) {
  const fs::path path =
      write("points.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
            "property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_THROW(load_mesh(path), DatasetError);
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

// Every directed edge of a closed, consistently wound mesh has its reverse exactly once.
bool closed_and_consistent(const Mesh& mesh) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      if (++directed[{t[k], t[(k + 1) % 3]}] > 1) return false;
    }
  }
  for (const auto& [edge, count] : directed) {
    if (directed.count({edge.second, edge.first}) == 0) return false;
  }
  return true;
}

double signed_volume(const Mesh& mesh) {
  double six_volume = 0;
  for (const auto& t : mesh.triangles) {
    six_volume += mesh.positions[t[0]].cast<double>().dot(
        mesh.positions[t[1]].cast<double>().cross(mesh.positions[t[2]].cast<double>()));
  }
  return six_volume / 6;
}

double surface_area(const Mesh& mesh) {
  double area = 0;
  for (const auto& t : mesh.triangles) {
    area += 0.5 * (mesh.positions[t[1]] - mesh.positions[t[0]])
                      .cast<double>()
                      .cross((mesh.positions[t[2]] - mesh.positions[t[0]]).cast<double>())
                      .norm();
  }
  return area;
}

// Distance from p to the nearest triangle of `mesh` (brute force).
double distance_to_mesh(const Eigen::Vector3d& p, const Mesh& mesh) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.positions[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.positions[t[2]].cast<double>();
    // Project onto the plane; inside the triangle that is the distance, else the nearest edge.
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    const Eigen::Vector3d q = p - n.dot(p - a) * n;
    const bool inside = (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
                        (a - c).cross(q - c).dot(n) >= 0;
    double d = std::abs(n.dot(p - a));
    if (!inside) {
      d = std::numeric_limits<double>::infinity();
      for (const auto& [e0, e1] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
        const double s = std::clamp((p - e0).dot(e1 - e0) / (e1 - e0).squaredNorm(), 0.0, 1.0);
        d = std::min(d, (p - (e0 + s * (e1 - e0))).norm());
      }
    }
    best = std::min(best, d);
  }
  return best;
}

// A closed lathe about z through (radius, z) profile points, bottom to top, with `segments`
// around and flat caps; vertices shared, wound outward.
Mesh lathe_mesh(const std::vector<Eigen::Vector2f>& profile, int segments) {
  Mesh mesh;
  const auto ring = static_cast<std::uint32_t>(segments);
  for (const auto& point : profile) {
    for (int i = 0; i < segments; ++i) {
      const double angle = 2.0 * M_PI * i / segments;
      mesh.positions.emplace_back(static_cast<float>(point.x() * std::cos(angle)),
                                  static_cast<float>(point.x() * std::sin(angle)), point.y());
    }
  }
  for (std::uint32_t p = 0; p + 1 < profile.size(); ++p) {
    for (std::uint32_t i = 0; i < ring; ++i) {
      const std::uint32_t a = p * ring + i, b = p * ring + (i + 1) % ring;
      mesh.triangles.push_back({a, b, b + ring});
      mesh.triangles.push_back({a, b + ring, a + ring});
    }
  }
  const auto bottom = static_cast<std::uint32_t>(mesh.positions.size());
  mesh.positions.emplace_back(0, 0, profile.front().y());
  mesh.positions.emplace_back(0, 0, profile.back().y());
  const auto top_ring = static_cast<std::uint32_t>(profile.size() - 1) * ring;
  for (std::uint32_t i = 0; i < ring; ++i) {
    mesh.triangles.push_back({bottom, (i + 1) % ring, i});
    mesh.triangles.push_back({bottom + 1, top_ring + i, top_ring + (i + 1) % ring});
  }
  return mesh;
}

// A UV sphere of radius r: `rings` rings of latitude between the poles.
Mesh sphere_mesh(float r, int rings, int segments) {
  std::vector<Eigen::Vector2f> profile;
  for (int j = 1; j <= rings; ++j) {
    const double polar = M_PI * (1.0 - static_cast<double>(j) / (rings + 1));
    profile.emplace_back(static_cast<float>(r * std::sin(polar)),
                         static_cast<float>(r * std::cos(polar)));
  }
  Mesh mesh = lathe_mesh(profile, segments);
  // Lift the cap centres to the poles.
  mesh.positions[mesh.positions.size() - 2] = Eigen::Vector3f(0, 0, -r);
  mesh.positions.back() = Eigen::Vector3f(0, 0, r);
  return mesh;
}

TEST(Decimate, SubdividedBoxBecomesItsTwelveTriangles) {
  // Vertices duplicated per face; 2028 and 768 triangles (the catalogue's boxes).
  for (const auto& [size, subdivisions] : {std::pair{Eigen::Vector3f(0.1f, 0.06f, 0.04f), 13},
                                           std::pair{Eigen::Vector3f(0.14f, 0.068f, 0.07f), 8}}) {
    const Mesh dense = box_mesh(size, subdivisions);
    DecimateOptions options;
    options.max_triangles = 200;
    DecimateSummary summary;
    const Mesh proxy = decimate(dense, options, &summary);
    EXPECT_EQ(proxy.triangle_count(), 12u);
    EXPECT_LT(summary.max_distance_m, 1e-9);
    EXPECT_EQ(proxy.positions.size(), 8u);
    EXPECT_EQ(proxy.normals.size(), proxy.positions.size());
    // Corners are kept exactly.
    EXPECT_EQ(proxy.bounds().min(), dense.bounds().min());
    EXPECT_EQ(proxy.bounds().max(), dense.bounds().max());
    for (const auto& p : proxy.positions) EXPECT_EQ(p.cwiseAbs(), size / 2);
    EXPECT_TRUE(closed_and_consistent(proxy));
    EXPECT_NEAR(signed_volume(proxy), size.prod(), 1e-9);
  }
}

TEST(Decimate, CylinderKeepsTheSidesItsChordErrorNeeds) {
  // r = 5 cm, 256 sides (chord error r (1 - cos(pi / 256)) = 3.8 um), 8 rings along z.
  const float r = 0.05f, half_height = 0.07f;
  std::vector<Eigen::Vector2f> profile;
  for (int j = 0; j <= 8; ++j) profile.emplace_back(r, -half_height + 2 * half_height * j / 8);
  const Mesh dense = lathe_mesh(profile, 256);
  ASSERT_EQ(dense.triangle_count(), 256u * 18);
  DecimateOptions options;
  options.max_triangles = 1000;
  options.tolerance_m = 0.0005;
  DecimateSummary summary;
  const Mesh proxy = decimate(dense, options, &summary);
  // Sides are planar strips and caps flat, so n sides need about 4n triangles; the chord error
  // r (1 - cos(pi / n)) <= 0.5 mm needs n >= 23.
  EXPECT_LE(proxy.triangle_count(), 4u * 48);
  EXPECT_GE(proxy.triangle_count(), 2u * 23);
  EXPECT_TRUE(closed_and_consistent(proxy));
  EXPECT_GT(signed_volume(proxy), 0);
  // Proxy vertices are vertices of the input, so on the true surface.
  const auto distance_to_cylinder = [&](const Eigen::Vector3d& p) {
    const double radial = std::hypot(p.x(), p.y()) - r, axial = std::abs(p.z()) - half_height;
    if (radial <= 0 && axial <= 0) return std::abs(std::max(radial, axial));
    return std::hypot(std::max(radial, 0.0), std::max(axial, 0.0));
  };
  for (const auto& p : proxy.positions) EXPECT_LT(distance_to_cylinder(p.cast<double>()), 1e-6);
  // Dense samples of the true surface (side and caps) lie within the tolerance of the proxy,
  // up to the input's own chord error and float rounding.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(0, 1);
  double worst = 0;
  for (int i = 0; i < 4000; ++i) {
    const double angle = 2 * M_PI * unit(rng);
    Eigen::Vector3d p;
    if (i % 2 == 0) {
      p = {r * std::cos(angle), r * std::sin(angle), half_height * (2 * unit(rng) - 1)};
    } else {
      const double radius = r * std::sqrt(unit(rng));
      p = {radius * std::cos(angle), radius * std::sin(angle),
           i % 4 == 1 ? half_height : -half_height};
    }
    worst = std::max(worst, distance_to_mesh(p, proxy));
  }
  std::printf("cylinder of %zu triangles -> %zu, worst distance of the true surface %.3f mm\n",
              dense.triangle_count(), proxy.triangle_count(), 1e3 * worst);
  EXPECT_LE(worst, options.tolerance_m + 1e-5);
  EXPECT_GT(worst, 0.5 * options.tolerance_m);  // it did use the tolerance
  // The summary bounds the distance of the input's vertices to the proxy, within the tolerance.
  double worst_vertex = 0;
  for (const auto& p : dense.positions) {
    worst_vertex = std::max(worst_vertex, distance_to_mesh(p.cast<double>(), proxy));
  }
  EXPECT_GE(summary.max_distance_m, worst_vertex - 1e-9);
  EXPECT_LE(summary.max_distance_m, options.tolerance_m);
}

TEST(Decimate, SphereMeetsTheCapClosedAndOutward) {
  const float r = 0.05f;
  const Mesh dense = sphere_mesh(r, 63, 128);  // 16128 triangles
  DecimateOptions options;
  options.max_triangles = 300;
  options.tolerance_m = 0;
  const Mesh proxy = decimate(dense, options);
  EXPECT_LE(proxy.triangle_count(), 300u);
  EXPECT_GE(proxy.triangle_count(), 296u);  // a sphere has no error-free collapse
  EXPECT_TRUE(closed_and_consistent(proxy));
  // All vertices are on the sphere, so the proxy lies inside the ball; a 300-triangle
  // inscribed polyhedron of well-spread vertices misses a few % of the volume.
  const double ball = 4.0 / 3.0 * M_PI * r * r * r;
  std::printf("sphere of %zu triangles -> %zu, volume %.4f of the ball's\n", dense.triangle_count(),
              proxy.triangle_count(), signed_volume(proxy) / ball);
  EXPECT_LT(signed_volume(proxy), ball);
  EXPECT_GT(signed_volume(proxy), 0.95 * ball);
}

TEST(Decimate, ScanSizedSphereReachesTheCap) {
  // 500k triangles, the size of the largest BOP scans; prints the time (no wall-clock assert).
  const float r = 0.05f;
  const Mesh dense = sphere_mesh(r, 500, 500);
  ASSERT_GE(dense.triangle_count(), 499000u);
  DecimateOptions options;
  options.max_triangles = 200;
  const auto start = std::chrono::steady_clock::now();
  const Mesh proxy = decimate(dense, options);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("sphere of %zu triangles -> %zu in %.2f s\n", dense.triangle_count(),
              proxy.triangle_count(), seconds);
  EXPECT_LE(proxy.triangle_count(), 200u);
  EXPECT_TRUE(closed_and_consistent(proxy));
  const double ball = 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_LT(signed_volume(proxy), ball);
  EXPECT_GT(signed_volume(proxy), 0.9 * ball);
}

TEST(Decimate, OpenSquareKeepsItsBorder) {
  // A 10 x 10 grid of 0.1 m in z = 0: 200 triangles, one open border.
  Mesh square;
  const int n = 10;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) square.positions.emplace_back(0.01f * i, 0.01f * j, 0.0f);
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const std::uint32_t a = j * (n + 1) + i, b = a + 1, c = a + (n + 1), d = c + 1;
      square.triangles.push_back({a, b, d});
      square.triangles.push_back({a, d, c});
    }
  }
  const Mesh proxy = decimate(square, DecimateOptions{});
  EXPECT_EQ(proxy.triangle_count(), 2u);
  EXPECT_EQ(proxy.bounds().min(), square.bounds().min());
  EXPECT_EQ(proxy.bounds().max(), square.bounds().max());
  EXPECT_NEAR(surface_area(proxy), surface_area(square), 1e-9);
  for (const auto& t : proxy.triangles) {
    EXPECT_GT((proxy.positions[t[1]] - proxy.positions[t[0]])
                  .cross(proxy.positions[t[2]] - proxy.positions[t[0]])
                  .z(),
              0);  // winding kept
  }

  // With a budget below what the tolerance allows on a curved sheet, border vertices still
  // only slide along the border: the proxy's bounds stay those of the sheet.
  Mesh sheet = square;
  for (auto& p : sheet.positions) p.z() = 2.0f * (p.x() - 0.05f) * (p.x() - 0.05f);
  DecimateOptions tight;
  tight.max_triangles = 20;
  const Mesh bent = decimate(sheet, tight);
  EXPECT_LE(bent.triangle_count(), 20u);
  EXPECT_EQ(bent.bounds().min().head<2>(), sheet.bounds().min().head<2>());
  EXPECT_EQ(bent.bounds().max().head<2>(), sheet.bounds().max().head<2>());
  for (const auto& p : bent.positions) {
    EXPECT_FLOAT_EQ(p.z(), 2.0f * (p.x() - 0.05f) * (p.x() - 0.05f));
  }
}

TEST(Decimate, SmallCurvedMeshIsKeptAtZeroTolerance) {
  const Mesh sphere = sphere_mesh(0.05f, 5, 8);  // 80 triangles, no flat part
  DecimateOptions options;
  options.max_triangles = 1000;
  options.tolerance_m = 0;
  const Mesh same = decimate(sphere, options);
  EXPECT_EQ(same.triangle_count(), sphere.triangle_count());
  EXPECT_EQ(same.positions, sphere.positions);
}

TEST(WeldVertices, MergesDuplicatesBySeamAndSignedZero) {
  // box_mesh repeats each corner once per face for flat normals: 24 vertices, 8 positions.
  const Mesh box = box_mesh({0.2f, 0.1f, 0.05f});
  ASSERT_EQ(box.positions.size(), 24u);
  const WeldedVertices welded = weld_vertices(box);
  EXPECT_EQ(welded.positions.size(), 8u);
  ASSERT_EQ(welded.index_of.size(), box.positions.size());
  for (std::size_t i = 0; i < box.positions.size(); ++i) {
    EXPECT_EQ(welded.positions[welded.index_of[i]], box.positions[i]) << i;
  }
  Mesh signed_zero;
  signed_zero.positions = {{0.0f, 1.0f, 0.0f}, {-0.0f, 1.0f, 0.0f}, {1.0f, 0.0f, 0.0f}};
  const WeldedVertices zero = weld_vertices(signed_zero);
  EXPECT_EQ(zero.positions.size(), 2u);
  EXPECT_EQ(zero.index_of, (std::vector<std::uint32_t>{0, 0, 1}));
}

TEST(Decimate, RejectsInvalidOptions) {
  DecimateOptions options;
  options.max_triangles = 3;
  EXPECT_THROW(decimate(box_mesh({1, 1, 1}), options), std::invalid_argument);
  options = DecimateOptions{};
  options.tolerance_m = -0.001;
  EXPECT_THROW(decimate(box_mesh({1, 1, 1}), options), std::invalid_argument);
  options.tolerance_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(decimate(box_mesh({1, 1, 1}), options), std::invalid_argument);
  std::string why;
  options = DecimateOptions{};
  options.max_triangles = 2;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_EQ(why, "max_triangles must be >= 4, got 2");
}

}  // namespace
}  // namespace clutterscope::datasets
