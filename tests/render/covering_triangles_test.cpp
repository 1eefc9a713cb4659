#include <gtest/gtest.h>

#include <clutterscope/render/covering_triangles.hpp>
#include <random>

namespace clutterscope::render {
namespace {

// Window positions are given directly: clip_from_model maps (x, y, z) to window (x, y) for a
// viewport of 2 x 2 pixels at (-1, -1), whose transform is window = ndc.
const Eigen::Matrix4d kWindowIsModel = Eigen::Matrix4d::Identity();
CoverageWindow window_of(int x, int y, int width, int height) {
  return {-1, -1, 2, 2, x, y, width, height};
}

std::size_t kept(const std::vector<Eigen::Vector2d>& corners, const CoverageWindow& window,
                 FaceSelection faces = FaceSelection::kAll) {
  std::vector<Eigen::Vector3f> positions;
  for (const Eigen::Vector2d& c : corners) positions.emplace_back(c.x(), c.y(), 0.5f);
  CoveringTriangles out;
  find_covering_triangles(positions, {{0, 1, 2}}, kWindowIsModel, window, faces, &out);
  EXPECT_EQ(out.indices.size(), 3 * out.kept);
  return out.kept;
}

// Pixel centre p inside or on the triangle (either orientation).
bool contains(const Eigen::Vector2d* v, const Eigen::Vector2d& p) {
  double signs[3];
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector2d& a = v[k];
    const Eigen::Vector2d& b = v[(k + 1) % 3];
    signs[k] = (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
  }
  return (signs[0] >= 0 && signs[1] >= 0 && signs[2] >= 0) ||
         (signs[0] <= 0 && signs[1] <= 0 && signs[2] <= 0);
}

TEST(CoveringTriangles, KeepsATriangleAroundAPixelCentre) {
  EXPECT_EQ(kept({{2.3, 3.3}, {2.7, 3.3}, {2.5, 3.8}}, window_of(0, 0, 8, 8)), 1u);
}

TEST(CoveringTriangles, DropsATinyTriangleBetweenPixelCentres) {
  // Box [2.6, 2.9] x [3.6, 3.9]: no centre (i + 0.5) within it, even widened by 1/32.
  EXPECT_EQ(kept({{2.6, 3.6}, {2.9, 3.6}, {2.75, 3.9}}, window_of(0, 0, 8, 8)), 0u);
}

TEST(CoveringTriangles, DropsATriangleWhoseBoxHoldsACentreOutsideIt) {
  // A sliver along the diagonal of pixel (2, 3)'s box that passes 0.1 px from its centre.
  EXPECT_EQ(kept({{2.0, 3.3}, {3.0, 4.3}, {2.2, 3.3}}, window_of(0, 0, 8, 8)), 0u);
  // Thinner still, its orientation is not sure: kept for GL to decide.
  EXPECT_EQ(kept({{2.0, 3.3}, {3.0, 4.3}, {2.05, 3.3}}, window_of(0, 0, 8, 8)), 1u);
}

TEST(CoveringTriangles, KeepsATriangleThatPassesWithinTheToleranceOfACentre) {
  // Its edge y = 3.5 - 0.01 passes 0.01 px below the centre (2.5, 3.5): snapping could cover it.
  EXPECT_EQ(kept({{2.0, 3.2}, {3.0, 3.2}, {2.5, 3.49}}, window_of(0, 0, 8, 8)), 1u);
}

TEST(CoveringTriangles, OnlyCentresInsideTheScissorBoxCount) {
  const std::vector<Eigen::Vector2d> around_centre = {{2.3, 3.3}, {2.7, 3.3}, {2.5, 3.8}};
  EXPECT_EQ(kept(around_centre, window_of(3, 0, 5, 8)), 0u);
  EXPECT_EQ(kept(around_centre, window_of(0, 4, 8, 4)), 0u);
  EXPECT_EQ(kept(around_centre, window_of(2, 3, 1, 1)), 1u);
  EXPECT_EQ(kept(around_centre, window_of(0, 0, 0, 0)), 0u);
}

TEST(CoveringTriangles, DropsOnlySurelyCulledFaces) {
  const std::vector<Eigen::Vector2d> counter_clockwise = {{1.1, 1.1}, {6.9, 1.2}, {3.0, 6.8}};
  const std::vector<Eigen::Vector2d> clockwise = {{1.1, 1.1}, {3.0, 6.8}, {6.9, 1.2}};
  const CoverageWindow window = window_of(0, 0, 8, 8);
  EXPECT_EQ(kept(counter_clockwise, window, FaceSelection::kCounterClockwise), 1u);
  EXPECT_EQ(kept(counter_clockwise, window, FaceSelection::kClockwise), 0u);
  EXPECT_EQ(kept(clockwise, window, FaceSelection::kClockwise), 1u);
  EXPECT_EQ(kept(clockwise, window, FaceSelection::kCounterClockwise), 0u);
  EXPECT_EQ(kept(clockwise, window, FaceSelection::kAll), 1u);
  // Degenerate (collinear) over a centre: its orientation is not sure, GL decides.
  EXPECT_EQ(kept({{1.0, 1.5}, {4.0, 1.5}, {6.0, 1.5}}, window, FaceSelection::kClockwise), 1u);
}

TEST(CoveringTriangles, KeepsTrianglesWithAVertexThatDoesNotProject) {
  // w = 0 for the vertex with z = 1 under this matrix (w = 1 - z).
  Eigen::Matrix4d clip = Eigen::Matrix4d::Identity();
  clip(3, 2) = -1;
  clip(3, 3) = 1;
  const std::vector<Eigen::Vector3f> positions = {
      {0.6f, 0.6f, 0}, {0.9f, 0.6f, 0}, {0.7f, 0.9f, 1}};
  CoveringTriangles out;
  find_covering_triangles(positions, {{0, 1, 2}}, clip, window_of(0, 0, 8, 8), FaceSelection::kAll,
                          &out);
  EXPECT_EQ(out.kept, 1u);
}

TEST(CoveringTriangles, NoDroppedTriangleCoversACentreWhenItsVerticesMoveWithinTheTolerance) {
  // Small random triangles around a few pixels, and for each dropped one, vertices moved by up
  // to 0.99 of the tolerance in random directions (what snapping and rounding may do): none of
  // the moved triangles may contain a pixel centre. 20,000 triangles x 16 moves.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> where(1.0, 5.0), offset(-0.8, 0.8), unit(-1.0, 1.0);
  const CoverageWindow window = window_of(0, 0, 8, 8);
  const double delta = CoverageTolerance{}.absolute_px;  // coordinates are small
  int dropped = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Eigen::Vector2d centre(where(rng), where(rng));
    const std::vector<Eigen::Vector2d> corners = {
        centre + Eigen::Vector2d(offset(rng), offset(rng)),
        centre + Eigen::Vector2d(offset(rng), offset(rng)),
        centre + Eigen::Vector2d(offset(rng), offset(rng))};
    if (kept(corners, window) == 1) continue;
    ++dropped;
    for (int move = 0; move < 16; ++move) {
      Eigen::Vector2d v[3];
      for (int k = 0; k < 3; ++k) {
        Eigen::Vector2d direction(unit(rng), unit(rng));
        if (direction.norm() > 0) direction.normalize();
        v[k] = corners[static_cast<std::size_t>(k)] + 0.99 * delta * direction;
      }
      for (int j = 0; j < 8; ++j) {
        for (int i = 0; i < 8; ++i) {
          ASSERT_FALSE(contains(v, Eigen::Vector2d(i + 0.5, j + 0.5)))
              << "trial " << trial << ": dropped, but covers pixel (" << i << ", " << j << ")";
        }
      }
    }
  }
  // The test means something only if many are dropped (tiny triangles mostly cover nothing).
  EXPECT_GT(dropped, 5000);
}

TEST(CoveringTriangles, KeepsEveryTriangleThatCoversACentre) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> where(1.0, 5.0), offset(-1.5, 1.5);
  const CoverageWindow window = window_of(0, 0, 8, 8);
  int covering = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Eigen::Vector2d centre(where(rng), where(rng));
    Eigen::Vector2d v[3];
    for (Eigen::Vector2d& corner : v) corner = centre + Eigen::Vector2d(offset(rng), offset(rng));
    bool covers = false;
    for (int j = 0; j < 8 && !covers; ++j) {
      for (int i = 0; i < 8 && !covers; ++i)
        covers = contains(v, Eigen::Vector2d(i + 0.5, j + 0.5));
    }
    if (!covers) continue;
    ++covering;
    ASSERT_EQ(kept({v[0], v[1], v[2]}, window), 1u) << "trial " << trial;
  }
  EXPECT_GT(covering, 5000);
}

}  // namespace
}  // namespace clutterscope::render
