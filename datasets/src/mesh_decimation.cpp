#include <algorithm>
#include <clutterscope/datasets/mesh.hpp>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <queue>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "mesh_normals.hpp"

// Quadric-error-metric decimation (decimate, see mesh.hpp).

namespace clutterscope::datasets {

namespace {

// Closest-point distance (squared) from p to the triangle abc (Ericson, Real-Time Collision
// Detection, 5.1.5).
double squared_distance_to_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (ap - d1 / (d1 - d3) * ab).squaredNorm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (ap - d2 / (d2 - d6) * ac).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    return (bp - (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)).squaredNorm();
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) {  // degenerate triangle: its corners bound the distance
    return std::min({ap.squaredNorm(), bp.squaredNorm(), cp.squaredNorm()});
  }
  return (ap - ab * (vb / sum) - ac * (vc / sum)).squaredNorm();
}

// Garland & Heckbert's fundamental error quadric: the error of x is [x 1] K [x 1]^T.
using Quadric = Eigen::Matrix4d;

Quadric plane_quadric(const Eigen::Vector3d& unit_normal, const Eigen::Vector3d& point,
                      double weight) {
  Eigen::Vector4d plane;
  plane << unit_normal, -unit_normal.dot(point);
  return weight * plane * plane.transpose();
}

double quadric_error(const Quadric& q, const Eigen::Vector3d& x) {
  const Eigen::Vector4d h(x.x(), x.y(), x.z(), 1.0);
  return std::max(0.0, h.dot(q * h));
}

// Boundary constraint planes weigh like this many faces of the edge's length squared: enough
// that sliding a border vertex off its line costs more than flattening interior detail.
constexpr double kBoundaryWeight = 10.0;

class Decimator {
 public:
  explicit Decimator(const Mesh& mesh) {
    weld(mesh);
    classify_edges();
    build_quadrics();
  }

  void run(const DecimateOptions& options) {
    tolerance_squared_ = options.tolerance_m * options.tolerance_m;
    for (std::uint32_t u = 0; u < position_.size(); ++u) push(u);
    if (live_faces_ <= options.max_triangles) start_tracking();
    while (!queue_.empty()) {
      const Candidate top = queue_.top();
      queue_.pop();
      if (!alive_[top.u] || top.version != version_[top.u]) continue;
      const std::vector<Target> targets = targets_of(top.u);
      for (std::size_t k = top.rank; k < targets.size(); ++k) {
        if (!queue_.empty() && targets[k].cost > queue_.top().cost) {
          queue_.push({targets[k].cost, top.u, version_[top.u], static_cast<std::uint32_t>(k)});
          break;
        }
        if (!allowed(top.u, targets[k].v)) continue;
        if (tracking_ && !within_tolerance(top.u, targets[k].v)) continue;
        collapse(top.u, targets[k].v);
        if (!tracking_ && live_faces_ <= options.max_triangles) start_tracking();
        break;
      }
    }
  }

  double max_distance() {
    // A mesh left above the budget (no allowed collapse) was never measured.
    if (!tracking_) start_tracking();
    double worst = 0;
    for (std::size_t f = 0; f < faces_.size(); ++f) {
      if (!face_alive_[f]) continue;
      const auto& t = faces_[f];
      for (const auto s : face_samples_[f]) {
        worst = std::max(worst, squared_distance_to_triangle(samples_[s], position_[t[0]],
                                                             position_[t[1]], position_[t[2]]));
      }
    }
    return std::sqrt(worst);
  }

  Mesh result() const {
    Mesh proxy;
    std::vector<std::uint32_t> index(position_.size(), 0);
    for (std::uint32_t v = 0; v < position_.size(); ++v) {
      if (!alive_[v] || vertex_faces_[v].empty()) continue;
      index[v] = static_cast<std::uint32_t>(proxy.positions.size());
      proxy.positions.push_back(original_[v]);
    }
    for (std::size_t f = 0; f < faces_.size(); ++f) {
      if (!face_alive_[f]) continue;
      const auto& t = faces_[f];
      proxy.triangles.push_back({index[t[0]], index[t[1]], index[t[2]]});
    }
    proxy.normals = detail::vertex_normals(proxy);
    return proxy;
  }

 private:
  struct Candidate {
    double cost;
    std::uint32_t u;
    std::uint32_t version;
    std::uint32_t rank;  // index into u's sorted targets; cheaper ones were refused
    // std::priority_queue puts the largest first: order by cost, then vertex, for determinism.
    bool operator<(const Candidate& other) const {
      if (cost != other.cost) return cost > other.cost;
      if (u != other.u) return u > other.u;
      return rank > other.rank;
    }
  };
  struct Target {
    double cost;
    std::uint32_t v;
  };

  void weld(const Mesh& mesh) {
    WeldedVertices welded = weld_vertices(mesh);
    original_ = std::move(welded.positions);
    const std::vector<std::uint32_t>& index_of = welded.index_of;
    position_.reserve(original_.size());
    for (const auto& p : original_) position_.push_back(p.cast<double>());
    vertex_faces_.resize(original_.size());
    for (const auto& t : mesh.triangles) {
      const std::array<std::uint32_t, 3> w = {index_of[t[0]], index_of[t[1]], index_of[t[2]]};
      if (w[0] == w[1] || w[1] == w[2] || w[2] == w[0]) continue;
      for (const auto v : w) vertex_faces_[v].push_back(static_cast<std::uint32_t>(faces_.size()));
      faces_.push_back(w);
    }
    original_faces_ = faces_;
    face_alive_.assign(faces_.size(), 1);
    live_faces_ = faces_.size();
    alive_.assign(original_.size(), 1);
    version_.assign(original_.size(), 0);
    merged_into_.resize(original_.size());
    for (std::uint32_t v = 0; v < merged_into_.size(); ++v) merged_into_[v] = v;
  }

  // Border vertices (an edge with one face) may only slide along their border; vertices of
  // non-manifold or inconsistently wound edges stay where they are.
  void classify_edges() {
    struct Use {
      int count = 0;
      int forward = 0;  // uses running from the smaller to the larger index
    };
    std::unordered_map<std::uint64_t, Use> edges;
    edges.reserve(faces_.size() * 2);
    for (const auto& t : faces_) {
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = t[k], b = t[(k + 1) % 3];
        Use& use = edges[(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b)];
        ++use.count;
        use.forward += a < b ? 1 : 0;
      }
    }
    boundary_.assign(position_.size(), 0);
    locked_.assign(position_.size(), 0);
    boundary_edges_.clear();
    for (const auto& [key, use] : edges) {
      const auto a = static_cast<std::uint32_t>(key >> 32);
      const auto b = static_cast<std::uint32_t>(key & 0xffffffffu);
      if (use.count == 1) {
        boundary_[a] = boundary_[b] = 1;
        boundary_edges_.push_back({a, b});
      } else if (use.count > 2 || use.forward != 1) {
        locked_[a] = locked_[b] = 1;
      }
    }
  }

  void build_quadrics() {
    quadric_.assign(position_.size(), Quadric::Zero());
    for (const auto& t : faces_) {
      const Eigen::Vector3d n =
          (position_[t[1]] - position_[t[0]]).cross(position_[t[2]] - position_[t[0]]);
      const double length = n.norm();
      if (!(length > 0)) continue;
      const Quadric k = plane_quadric(n / length, position_[t[0]], 0.5 * length);
      for (const auto v : t) quadric_[v] += k;
    }
    for (const auto& [a, b] : boundary_edges_) {
      // The plane through the edge perpendicular to its face.
      for (const auto f : vertex_faces_[a]) {
        const auto& t = faces_[f];
        if (std::find(t.begin(), t.end(), b) == t.end()) continue;
        const Eigen::Vector3d n =
            (position_[t[1]] - position_[t[0]]).cross(position_[t[2]] - position_[t[0]]);
        const Eigen::Vector3d edge = position_[b] - position_[a];
        const Eigen::Vector3d m = edge.cross(n);
        if (!(m.norm() > 0)) continue;
        const Quadric k =
            plane_quadric(m.normalized(), position_[a], kBoundaryWeight * edge.squaredNorm());
        quadric_[a] += k;
        quadric_[b] += k;
      }
    }
  }

  void neighbours(std::uint32_t u, std::vector<std::uint32_t>* out) const {
    out->clear();
    for (const auto f : vertex_faces_[u]) {
      for (const auto w : faces_[f]) {
        if (w != u) out->push_back(w);
      }
    }
    std::sort(out->begin(), out->end());
    out->erase(std::unique(out->begin(), out->end()), out->end());
  }

  std::vector<Target> targets_of(std::uint32_t u) const {
    std::vector<std::uint32_t> ring;
    neighbours(u, &ring);
    std::vector<Target> targets;
    targets.reserve(ring.size());
    for (const auto v : ring) {
      targets.push_back({quadric_error(quadric_[u] + quadric_[v], position_[v]), v});
    }
    std::sort(targets.begin(), targets.end(), [](const Target& a, const Target& b) {
      return a.cost != b.cost ? a.cost < b.cost : a.v < b.v;
    });
    return targets;
  }

  void push(std::uint32_t u) {
    if (!alive_[u] || locked_[u] || vertex_faces_[u].empty()) return;
    const std::vector<Target> targets = targets_of(u);
    if (!targets.empty()) queue_.push({targets.front().cost, u, version_[u], 0});
  }

  // The face f with u replaced by v.
  std::array<std::uint32_t, 3> moved(std::uint32_t f, std::uint32_t u, std::uint32_t v) const {
    std::array<std::uint32_t, 3> t = faces_[f];
    for (auto& w : t) {
      if (w == u) w = v;
    }
    return t;
  }

  Eigen::Vector3d normal(const std::array<std::uint32_t, 3>& t) const {
    return (position_[t[1]] - position_[t[0]]).cross(position_[t[2]] - position_[t[0]]);
  }

  static bool contains(const std::array<std::uint32_t, 3>& t, std::uint32_t w) {
    return t[0] == w || t[1] == w || t[2] == w;
  }

  bool allowed(std::uint32_t u, std::uint32_t v) {
    // Faces on the edge, and their third vertices.
    std::vector<std::uint32_t> opposite;
    for (const auto f : vertex_faces_[u]) {
      const auto& t = faces_[f];
      if (!contains(t, v)) continue;
      for (const auto w : t) {
        if (w != u && w != v) opposite.push_back(w);
      }
    }
    if (opposite.empty() || opposite.size() > 2) return false;
    // A border vertex slides along its border only.
    if (boundary_[u] && opposite.size() != 1) return false;
    // Link condition: the one-rings of u and v share exactly the edge's opposite vertices.
    neighbours(u, &ring_u_);
    neighbours(v, &ring_v_);
    std::size_t shared = 0;
    for (auto a = ring_u_.begin(), b = ring_v_.begin(); a != ring_u_.end() && b != ring_v_.end();) {
      if (*a < *b) {
        ++a;
      } else if (*b < *a) {
        ++b;
      } else {
        ++shared;
        ++a;
        ++b;
      }
    }
    std::sort(opposite.begin(), opposite.end());
    if (std::unique(opposite.begin(), opposite.end()) != opposite.end()) return false;
    if (shared != opposite.size()) return false;
    for (const auto f : vertex_faces_[u]) {
      if (contains(faces_[f], v)) continue;
      const std::array<std::uint32_t, 3> after = moved(f, u, v);
      // No flipped or degenerate triangle.
      const Eigen::Vector3d n_before = normal(faces_[f]);
      const Eigen::Vector3d n_after = normal(after);
      double longest = 0;
      for (int k = 0; k < 3; ++k) {
        longest =
            std::max(longest, (position_[after[k]] - position_[after[(k + 1) % 3]]).squaredNorm());
      }
      if (!(n_after.norm() > 1e-9 * longest)) return false;
      if (n_before.norm() > 0 && !(n_after.dot(n_before) > 0)) return false;
      // No face twice (the collapse of a tetrahedron's edge would leave two back-to-back faces).
      for (const auto g : vertex_faces_[v]) {
        const auto& t = faces_[g];
        if (!contains(t, u) && contains(t, after[0]) && contains(t, after[1]) &&
            contains(t, after[2])) {
          return false;
        }
      }
    }
    return true;
  }

  // Samples (original vertices and face centroids) of the faces around u, reassigned to the
  // nearest face around v after u -> v; true when all stay within the tolerance. Fills
  // assignment_ for collapse().
  bool within_tolerance(std::uint32_t u, std::uint32_t v) {
    ring_faces_.clear();
    ring_triangles_.clear();
    for (const auto f : vertex_faces_[v]) {
      if (contains(faces_[f], u)) continue;
      ring_faces_.push_back(f);
      ring_triangles_.push_back(faces_[f]);
    }
    for (const auto f : vertex_faces_[u]) {
      if (contains(faces_[f], v)) continue;
      ring_faces_.push_back(f);
      ring_triangles_.push_back(moved(f, u, v));
    }
    assignment_.clear();
    for (const auto f : vertex_faces_[u]) {
      for (const auto s : face_samples_[f]) {
        double best = std::numeric_limits<double>::infinity();
        std::uint32_t best_face = 0;
        for (std::size_t r = 0; r < ring_faces_.size(); ++r) {
          const auto& t = ring_triangles_[r];
          const double d = squared_distance_to_triangle(samples_[s], position_[t[0]],
                                                        position_[t[1]], position_[t[2]]);
          if (d < best) {
            best = d;
            best_face = ring_faces_[r];
          }
        }
        if (!(best <= tolerance_squared_)) return false;
        assignment_.push_back({s, best_face});
      }
    }
    return true;
  }

  void collapse(std::uint32_t u, std::uint32_t v) {
    const std::vector<std::uint32_t> faces_of_u = vertex_faces_[u];
    for (const auto f : faces_of_u) {
      if (contains(faces_[f], v)) {
        face_alive_[f] = 0;
        --live_faces_;
        for (const auto w : faces_[f]) {
          if (w == u) continue;
          auto& list = vertex_faces_[w];
          list.erase(std::find(list.begin(), list.end(), f));
        }
      } else {
        faces_[f] = moved(f, u, v);
        vertex_faces_[v].push_back(f);
      }
    }
    if (tracking_) {
      for (const auto f : faces_of_u) face_samples_[f].clear();
      for (const auto& [s, f] : assignment_) face_samples_[f].push_back(s);
    }
    vertex_faces_[u].clear();
    alive_[u] = 0;
    merged_into_[u] = v;
    quadric_[v] += quadric_[u];
    neighbours(v, &ring_v_);
    const std::vector<std::uint32_t> affected = ring_v_;
    ++version_[v];
    push(v);
    for (const auto w : affected) {
      ++version_[w];
      push(w);
    }
  }

  std::uint32_t representative(std::uint32_t v) {
    while (merged_into_[v] != v) {
      merged_into_[v] = merged_into_[merged_into_[v]];
      v = merged_into_[v];
    }
    return v;
  }

  double squared_distance(const Eigen::Vector3d& sample, std::uint32_t f) const {
    const auto& t = faces_[f];
    return squared_distance_to_triangle(sample, position_[t[0]], position_[t[1]], position_[t[2]]);
  }

  // From here on every collapse is measured: the original vertices and face centroids are
  // assigned to their nearest face, found from the faces around the vertices they were merged
  // into by walking to neighbouring faces while the distance shrinks (the face around the
  // representative may lie far away in the same plane).
  void start_tracking() {
    tracking_ = true;
    face_samples_.assign(faces_.size(), {});
    const auto assign = [&](const Eigen::Vector3d& sample,
                            std::initializer_list<std::uint32_t> origins) {
      double best = std::numeric_limits<double>::infinity();
      std::uint32_t best_face = 0;
      for (const auto origin : origins) {
        for (const auto f : vertex_faces_[representative(origin)]) {
          const double d = squared_distance(sample, f);
          if (d < best) {
            best = d;
            best_face = f;
          }
        }
      }
      if (best < std::numeric_limits<double>::infinity()) {
        for (bool closer = true; closer;) {
          closer = false;
          const std::array<std::uint32_t, 3> corners = faces_[best_face];
          for (const auto w : corners) {
            for (const auto f : vertex_faces_[w]) {
              const double d = squared_distance(sample, f);
              if (d < best) {
                best = d;
                best_face = f;
                closer = true;
              }
            }
          }
        }
        face_samples_[best_face].push_back(static_cast<std::uint32_t>(samples_.size()));
        samples_.push_back(sample);
      }
    };
    for (std::uint32_t v = 0; v < original_.size(); ++v) {
      assign(position_[v], {v});
    }
    for (const auto& t : original_faces_) {
      assign((position_[t[0]] + position_[t[1]] + position_[t[2]]) / 3.0, {t[0], t[1], t[2]});
    }
  }

  std::vector<Eigen::Vector3f> original_;  // welded positions, kept exactly in the proxy
  std::vector<Eigen::Vector3d> position_;
  std::vector<Quadric> quadric_;
  std::vector<std::array<std::uint32_t, 3>> faces_;
  std::vector<std::array<std::uint32_t, 3>> original_faces_;
  std::vector<char> face_alive_;
  std::size_t live_faces_ = 0;
  std::vector<std::vector<std::uint32_t>> vertex_faces_;
  std::vector<char> alive_, boundary_, locked_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary_edges_;
  std::vector<std::uint32_t> version_;
  std::vector<std::uint32_t> merged_into_;
  std::priority_queue<Candidate> queue_;

  double tolerance_squared_ = 0;
  bool tracking_ = false;
  std::vector<Eigen::Vector3d> samples_;
  std::vector<std::vector<std::uint32_t>> face_samples_;

  // Scratch space reused between collapses.
  std::vector<std::uint32_t> ring_u_, ring_v_, ring_faces_;
  std::vector<std::array<std::uint32_t, 3>> ring_triangles_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> assignment_;
};

}  // namespace

bool DecimateOptions::IsValid(std::string* why) const {
  if (max_triangles < 4) {
    if (why != nullptr) *why = "max_triangles must be >= 4, got " + std::to_string(max_triangles);
    return false;
  }
  if (!(tolerance_m >= 0) || !std::isfinite(tolerance_m)) {
    if (why != nullptr)
      *why = "tolerance_m must be finite and >= 0, got " + std::to_string(tolerance_m);
    return false;
  }
  return true;
}
Mesh decimate(const Mesh& mesh, const DecimateOptions& options, DecimateSummary* summary) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("DecimateOptions: " + why);
  Decimator decimator(mesh);
  decimator.run(options);
  if (summary != nullptr) summary->max_distance_m = decimator.max_distance();
  return decimator.result();
}

}  // namespace clutterscope::datasets
