// Procedural city along the driven path: streets (ground, curbs, markings), lots with buildings,
// yards and fences, street furniture, trees and parked cars. Deterministic by seed.
#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "sim/city_path.hpp"
#include "sim/city_world_impl.hpp"
#include "sim/random.hpp"

namespace slam_mms::sim {
namespace {

Eigen::Matrix3f Frame(const Eigen::Vector2d& t) {
  Eigen::Matrix3f R;
  R.col(0) = Eigen::Vector3f(static_cast<float>(t.x()), static_cast<float>(t.y()), 0.f);
  R.col(1) = Eigen::Vector3f(static_cast<float>(-t.y()), static_cast<float>(t.x()), 0.f);
  R.col(2) = Eigen::Vector3f::UnitZ();
  return R;
}

class Generator {
 public:
  Generator(const std::vector<CityWorld::PathSpan>& spans, bool either_direction,
            CityWorld::Impl* impl)
      : spans_(spans),
        either_direction_(either_direction),
        impl_(impl),
        o_(impl->options),
        rng_(MixSeed(o_.seed, 2)),
        veg_rng_(MixSeed(o_.seed, 7)) {}

  Status Run() {
    auto samples = SamplePaths(spans_, o_.body_height_above_road_m);
    // Several paths: an extension must not lower or raise another path's driven street. (One
    // path keeps its extensions' heights: its world stays as it was.)
    if (either_direction_) MatchExtensionHeights(&samples);
    AssignStreets(o_, either_direction_, &samples);
    impl_->path = PathIndex(std::move(samples), 8.0, o_.corridor_m + 12.0);
    impl_->has_path = true;
    BuildGround();
    BuildObjects();
    impl_->stats.num_hedges = num_hedges_;
    if (!impl_->mesh.mean_free_path_m.empty())
      impl_->mesh.mean_free_path_m.resize(impl_->mesh.triangles.size(), 0.f);
    double length = 0.0;
    for (const CityWorld::PathSpan& span : spans_) {
      const ReferenceTrajectory& traj = *span.trajectory;
      for (double t = span.t_begin_s + 0.1; t <= span.t_end_s; t += 0.1)
        length += (traj.Pose(t).translation() - traj.Pose(t - 0.1).translation()).norm();
    }
    impl_->stats.path_length_m = length;
    return OkStatus();
  }

 private:
  const PathIndex& path() const { return impl_->path; }

  // ---- ground --------------------------------------------------------------------------------
  void BuildGround() {
    TriangleMesh& mesh = impl_->mesh;
    const double tile = 8.0;
    const Eigen::Vector2d lo = path().min(), hi = path().max();
    const int ntx = static_cast<int>(std::ceil((hi.x() - lo.x()) / tile));
    const int nty = static_cast<int>(std::ceil((hi.y() - lo.y()) / tile));
    for (int ty = 0; ty < nty; ++ty) {
      for (int tx = 0; tx < ntx; ++tx) {
        const Eigen::Vector2d corner = lo + Eigen::Vector2d(tx * tile, ty * tile);
        const Eigen::Vector2d center = corner + Eigen::Vector2d::Constant(tile / 2);
        const PathNearest n = path().Nearest(center, o_.corridor_m + 6.0);
        if (n.segment < 0) continue;
        const PathSample& st = path().SampleOf(n);
        const bool fine = n.distance < st.half_width + st.sidewalk + 12.0;
        const double r = fine ? o_.ground_cell_m : 2.0;
        const int k = static_cast<int>(std::round(tile / r));
        GroundTile(corner, r, k, fine);
      }
    }
    impl_->num_ground_vertices = mesh.vertices.size();
    impl_->num_ground_triangles = mesh.triangles.size();
    impl_->stats.num_ground_triangles = mesh.triangles.size();
  }

  void GroundTile(const Eigen::Vector2d& corner, double r, int k, bool snap) {
    TriangleMesh& mesh = impl_->mesh;
    const int base = static_cast<int>(mesh.vertices.size());
    std::vector<float> signed_d((k + 1) * (k + 1)), dist((k + 1) * (k + 1));
    std::vector<const PathSample*> street((k + 1) * (k + 1));
    for (int j = 0; j <= k; ++j) {
      for (int i = 0; i <= k; ++i) {
        Eigen::Vector2d q = corner + Eigen::Vector2d(i * r, j * r);
        const PathNearest n = path().Nearest(q, o_.corridor_m + 40.0);
        const int idx = j * (k + 1) + i;
        if (n.segment < 0) {
          mesh.vertices.emplace_back(q.x(), q.y(), 0.f);
          impl_->vertex_d.push_back(1e9f);
          impl_->vertex_s.push_back(0.f);
          impl_->vertex_w.push_back(0.f);
          dist[idx] = 1e9f;
          signed_d[idx] = 1e9f;
          street[idx] = nullptr;
          continue;
        }
        const PathSample& s = path().SampleOf(n);
        double d = n.distance;
        double sd = d - s.half_width;
        // Snap vertices near the curb line onto it so the curb is a (near) vertical step.
        if (snap && std::abs(sd) < 0.7 * r && d > 1e-3) {
          const Eigen::Vector2d g = (q - n.foot) / d;
          const double target = sd < 0 ? -0.004 : 0.004;
          q += g * (target - sd);
          d += target - sd;
          sd = target;
        }
        double z = path().ZRoad(n) - 0.02 * std::min(d, s.half_width);
        if (sd > 0) z += o_.curb_height_m + 0.01 * std::min(sd, s.sidewalk);
        mesh.vertices.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()),
                                   static_cast<float>(z));
        impl_->vertex_d.push_back(static_cast<float>(d));
        impl_->vertex_s.push_back(static_cast<float>(path().SCanonical(n)));
        impl_->vertex_w.push_back(static_cast<float>(s.half_width));
        dist[idx] = static_cast<float>(d);
        signed_d[idx] = static_cast<float>(sd);
        street[idx] = &s;
      }
    }
    auto add = [&](int a, int b, int c) {
      const int ids[3] = {a, b, c};
      float mn = 1e9f, mx = -1e9f, dmin = 1e9f;
      bool beyond_sidewalk = false;
      for (int id : ids) {
        if (street[id] == nullptr) return;
        mn = std::min(mn, signed_d[id]);
        mx = std::max(mx, signed_d[id]);
        dmin = std::min(dmin, dist[id]);
        if (signed_d[id] > street[id]->sidewalk + 0.01) beyond_sidewalk = true;
      }
      if (dmin > o_.corridor_m) return;
      SurfaceClass cls;
      float albedo;
      if (mx <= 0.f) {
        cls = SurfaceClass::kRoad;
        albedo = 0.14f;
      } else if (mn < 0.f) {
        cls = SurfaceClass::kCurb;
        albedo = 0.38f;
      } else if (!beyond_sidewalk) {
        cls = SurfaceClass::kSidewalk;
        albedo = 0.30f;
      } else {
        cls = SurfaceClass::kTerrain;
        albedo = 0.22f;
      }
      mesh.triangles.emplace_back(base + a, base + b, base + c);
      mesh.classes.push_back(cls);
      mesh.albedo.push_back(albedo);
    };
    for (int j = 0; j < k; ++j) {
      for (int i = 0; i < k; ++i) {
        const int v00 = j * (k + 1) + i, v10 = v00 + 1, v01 = v00 + k + 1, v11 = v01 + 1;
        add(v00, v10, v11);
        add(v00, v11, v01);
      }
    }
  }

  // ---- lots and objects ---------------------------------------------------------------------
  static int64_t CellKey(int64_t x, int64_t y) {
    return static_cast<int64_t>((static_cast<uint64_t>(x) << 32) ^
                                static_cast<uint64_t>(y & 0xffffffffLL));
  }

  // True where (x, y) is free of streets (road + sidewalk + clearance) and of placed objects.
  bool PointFree(const Eigen::Vector2d& q, double clearance) const {
    const PathNearest n = path().Nearest(q, 40.0);
    if (n.segment >= 0) {
      const PathSample& s = path().SampleOf(n);
      if (n.distance < s.half_width + s.sidewalk + clearance) return false;
    }
    const int64_t key =
        CellKey(static_cast<int64_t>(std::floor(q.x())), static_cast<int64_t>(std::floor(q.y())));
    return occupied_.count(key) == 0 && (!check_furniture_ || furniture_.count(key) == 0);
  }

  bool RectFree(const Eigen::Vector2d& c, const Eigen::Vector2d& t, double hl, double hd,
                double clearance) const {
    const Eigen::Vector2d nrm(-t.y(), t.x());
    const int nl = std::max(1, static_cast<int>(std::ceil(2 * hl / 0.7)));
    const int nd = std::max(1, static_cast<int>(std::ceil(2 * hd / 0.7)));
    for (int a = 0; a <= nl; ++a)
      for (int b = 0; b <= nd; ++b)
        if (!PointFree(c + t * (-hl + 2 * hl * a / nl) + nrm * (-hd + 2 * hd * b / nd), clearance))
          return false;
    return true;
  }

  // Street furniture (trees, poles, cars) goes into its own set: it must not block the buildings
  // behind the sidewalk, but nothing may be placed onto it.
  void MarkFurniture(const Eigen::Vector2d& c, const Eigen::Vector2d& t, double hl, double hd) {
    std::swap(occupied_, furniture_);
    MarkRect(c, t, hl, hd);
    std::swap(occupied_, furniture_);
  }

  bool Occupied(const Eigen::Vector2d& q) const {
    const int64_t key =
        CellKey(static_cast<int64_t>(std::floor(q.x())), static_cast<int64_t>(std::floor(q.y())));
    return occupied_.count(key) != 0 || furniture_.count(key) != 0;
  }

  void MarkRect(const Eigen::Vector2d& c, const Eigen::Vector2d& t, double hl, double hd) {
    const Eigen::Vector2d nrm(-t.y(), t.x());
    const int nl = std::max(1, static_cast<int>(std::ceil(2 * hl / 0.5)));
    const int nd = std::max(1, static_cast<int>(std::ceil(2 * hd / 0.5)));
    for (int a = 0; a <= nl; ++a)
      for (int b = 0; b <= nd; ++b) {
        const Eigen::Vector2d q = c + t * (-hl + 2 * hl * a / nl) + nrm * (-hd + 2 * hd * b / nd);
        occupied_.insert(CellKey(static_cast<int64_t>(std::floor(q.x())),
                                 static_cast<int64_t>(std::floor(q.y()))));
      }
  }

  double Ground(const Eigen::Vector2d& q) const {
    return impl_->GroundModelHeight(q, nullptr, nullptr);
  }

  Eigen::Vector3f P3(const Eigen::Vector2d& q, double z) const {
    return Eigen::Vector3f(static_cast<float>(q.x()), static_cast<float>(q.y()),
                           static_cast<float>(z));
  }

  // A building block footprint (centre c, tangent t, half length hl, half depth hd; the depth axis
  // points away from the street along `away`), with upper setbacks and floor ledges.
  void EmitBuilding(const Eigen::Vector2d& c, const Eigen::Vector2d& t, const Eigen::Vector2d& away,
                    double hl, double hd, double height) {
    TriangleMesh& m = impl_->mesh;
    const float albedo = static_cast<float>(rng_.Uniform(0.22, 0.6));
    const double z0 = Ground(c);
    const Eigen::Matrix3f R = Frame(t);
    const Eigen::Vector2d nrm(-t.y(), t.x());
    const double sgn = nrm.dot(away) > 0 ? 1.0 : -1.0;  // depth axis sign in the frame
    double lower_h = height;
    if (height > 12.0 && rng_.Bernoulli(0.35)) {
      lower_h = height * rng_.Uniform(0.45, 0.7);
      const double recess = rng_.Uniform(1.5, 3.0);
      const Eigen::Vector2d cu = c + away * (recess / 2);
      const double zb = z0 + lower_h, zt = z0 + height;
      m.AddBox(P3(cu, (zb + zt) / 2), R,
               Eigen::Vector3f(static_cast<float>(hl - 0.5), static_cast<float>(hd - recess / 2),
                               static_cast<float>((zt - zb) / 2)),
               SurfaceClass::kBuilding, albedo);
    }
    const double zb = z0 - 1.0, zt = z0 + lower_h;
    m.AddBox(P3(c, (zb + zt) / 2), R,
             Eigen::Vector3f(static_cast<float>(hl), static_cast<float>(hd),
                             static_cast<float>((zt - zb) / 2)),
             SurfaceClass::kBuilding, albedo);
    (void)sgn;
    if (rng_.Bernoulli(0.45)) {  // floor ledges on the street facade
      const Eigen::Vector2d front = c - away * (hd + 0.15);
      for (double zf = 3.4; zf < lower_h - 1.0; zf += 3.3) {
        m.AddBox(P3(front, z0 + zf), R, Eigen::Vector3f(static_cast<float>(hl), 0.15f, 0.12f),
                 SurfaceClass::kBuilding, albedo * 1.1f);
      }
    }
    if (rng_.Bernoulli(0.3)) {  // ground-floor shop canopy
      const Eigen::Vector2d front = c - away * (hd + 0.6);
      m.AddBox(P3(front, z0 + 3.0), R, Eigen::Vector3f(static_cast<float>(hl * 0.6), 0.6f, 0.05f),
               SurfaceClass::kBuilding, static_cast<float>(rng_.Uniform(0.2, 0.7)));
    }
    ++impl_->stats.num_buildings;
  }

  bool TryBuilding(const Eigen::Vector2d& origin, const Eigen::Vector2d& t,
                   const Eigen::Vector2d& away, double front_offset, double length, double depth,
                   double height) {
    for (int attempt = 0; attempt < 3; ++attempt) {
      const double L = length * (attempt == 0 ? 1.0 : attempt == 1 ? 0.6 : 0.35);
      const double D = depth * (attempt == 2 ? 0.6 : 1.0);
      const Eigen::Vector2d c = origin + t * (L / 2) + away * (front_offset + D / 2);
      // Checked and marked 0.6 m inside the footprint so that neighbours may touch (1 m cells);
      // the street clearance (0.2 m) stays below the 0.3 m gap to the sidewalk.
      if (L < 5.0 || !RectFree(c, t, L / 2 - 0.6, D / 2 - 0.6, 0.2)) continue;
      if (!PointFree(c - away * (D / 2), 0.2)) continue;
      MarkRect(c, t, L / 2 - 0.6, D / 2 - 0.6);
      EmitBuilding(c, t, away, L / 2, D / 2, height);
      return true;
    }
    return false;
  }

  void EmitFence(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    TriangleMesh& m = impl_->mesh;
    const Eigen::Vector2d d = b - a;
    const double len = d.norm();
    if (len < 1.0) return;
    const Eigen::Vector2d t = d / len;
    const Eigen::Matrix3f R = Frame(t);
    const double h = rng_.Uniform(1.0, 2.0);
    const float albedo = static_cast<float>(rng_.Uniform(0.3, 0.6));
    const double z0 = Ground((a + b) / 2);
    if (rng_.Bernoulli(0.5)) {  // solid panel fence
      m.AddBox(
          P3((a + b) / 2, z0 + h / 2 - 0.05), R,
          Eigen::Vector3f(static_cast<float>(len / 2), 0.03f, static_cast<float>(h / 2 + 0.05)),
          SurfaceClass::kFence, albedo);
    } else {  // slatted: posts, rails, slats with gaps
      for (double s = 0; s <= len; s += 2.0)
        m.AddBox(P3(a + t * s, z0 + h / 2), R,
                 Eigen::Vector3f(0.05f, 0.05f, static_cast<float>(h / 2 + 0.1)),
                 SurfaceClass::kFence, albedo);
      for (double zr : {0.3, h - 0.2})
        m.AddBox(P3((a + b) / 2, z0 + zr), R,
                 Eigen::Vector3f(static_cast<float>(len / 2), 0.02f, 0.04f), SurfaceClass::kFence,
                 albedo);
      for (double s = 0.07; s < len; s += 0.16)
        m.AddBox(P3(a + t * s, z0 + h / 2), R,
                 Eigen::Vector3f(0.035f, 0.01f, static_cast<float>(h / 2 - 0.05)),
                 SurfaceClass::kFence, albedo);
    }
    ++impl_->stats.num_fences;
  }

  void EmitTree(const Eigen::Vector2d& q) {
    TriangleMesh& m = impl_->mesh;
    const double z0 = Ground(q);
    const double trunk_h = rng_.Uniform(2.0, 3.5);
    m.AddCylinder(P3(q, z0 - 0.2), static_cast<float>(rng_.Uniform(0.12, 0.25)),
                  static_cast<float>(trunk_h + 0.8), 7, SurfaceClass::kTrunk, 0.3f);
    const double rc = rng_.Uniform(1.6, 3.2);
    const double rz = rc * rng_.Uniform(0.8, 1.25);
    const Eigen::Vector3d center(q.x(), q.y(), z0 + trunk_h + rz * 0.8);
    const int leaves = static_cast<int>(420.0 * (rc / 2.5) * (rc / 2.5));
    const float albedo = static_cast<float>(rng_.Uniform(0.22, 0.4));
    for (int i = 0; i < leaves; ++i) {
      Eigen::Vector3d u(rng_.Normal(), rng_.Normal(), rng_.Normal());
      u.normalize();
      const double r = std::pow(rng_.Uniform(), 0.35);
      const Eigen::Vector3d p = center + Eigen::Vector3d(u.x() * rc, u.y() * rc, u.z() * rz) * r;
      Eigen::Vector3d e1(rng_.Normal(), rng_.Normal(), rng_.Normal());
      Eigen::Vector3d e2(rng_.Normal(), rng_.Normal(), rng_.Normal());
      e1 = e1.normalized() * 0.35;
      e2 = e2.normalized() * 0.35;
      // With volumetric vegetation the leaves are still drawn (the same random sequence keeps
      // the rest of the world unchanged) but the crown is a scattering hull instead.
      if (o_.volumetric_vegetation) continue;
      m.AddTriangle(p.cast<float>(), (p + e1).cast<float>(), (p + e2).cast<float>(),
                    SurfaceClass::kFoliage, albedo);
    }
    if (o_.volumetric_vegetation) EmitCrownHull(center, rc, rz, albedo);
    ++impl_->stats.num_trees;
  }

  // A closed, lumpy ellipsoid (semi-axes rc, rc, rz, each vertex's radius scaled by 0.85-1.15),
  // wound outward, marked as a scattering volume of the foliage mean free path.
  void EmitCrownHull(const Eigen::Vector3d& c, double rc, double rz, float albedo) {
    TriangleMesh& m = impl_->mesh;
    const size_t first = m.triangles.size();
    constexpr int kLat = 7, kLon = 14;
    std::vector<Eigen::Vector3f> v((kLat - 1) * kLon);
    auto at = [&](int i, int j) -> Eigen::Vector3f& { return v[(i - 1) * kLon + (j % kLon)]; };
    for (int i = 1; i < kLat; ++i) {
      const double th = M_PI * i / kLat;
      for (int j = 0; j < kLon; ++j) {
        const double ph = 2.0 * M_PI * (j + 0.5 * (i % 2)) / kLon;
        const double k = veg_rng_.Uniform(0.85, 1.15);
        at(i, j) = (c + k * Eigen::Vector3d(rc * std::sin(th) * std::cos(ph),
                                            rc * std::sin(th) * std::sin(ph), rz * std::cos(th)))
                       .cast<float>();
      }
    }
    const Eigen::Vector3f top =
        (c + Eigen::Vector3d(0, 0, rz * veg_rng_.Uniform(0.85, 1.15))).cast<float>();
    const Eigen::Vector3f bottom =
        (c - Eigen::Vector3d(0, 0, rz * veg_rng_.Uniform(0.85, 1.15))).cast<float>();
    const Eigen::Vector3f cf = c.cast<float>();
    auto tri = [&](const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& d) {
      const Eigen::Vector3f n = (b - a).cross(d - a);
      if (n.dot((a + b + d) / 3.f - cf) >= 0.f) {
        m.AddTriangle(a, b, d, SurfaceClass::kFoliage, albedo);
      } else {
        m.AddTriangle(a, d, b, SurfaceClass::kFoliage, albedo);
      }
    };
    for (int j = 0; j < kLon; ++j) {
      tri(top, at(1, j), at(1, j + 1));
      tri(bottom, at(kLat - 1, j), at(kLat - 1, j + 1));
      for (int i = 1; i + 1 < kLat; ++i) {
        tri(at(i, j), at(i + 1, j), at(i + 1, j + 1));
        tri(at(i, j), at(i + 1, j + 1), at(i, j + 1));
      }
    }
    m.MarkVolume(first, static_cast<float>(o_.foliage_mean_free_path_m));
  }

  // A hedge along a -> b on the side `away` points to: a box hull 0.6-1.2 m deep, 0.8-1.8 m high,
  // a scattering volume of the hedge mean free path. Uses only veg_rng_.
  void EmitHedge(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& away) {
    const Eigen::Vector2d d = b - a;
    const double len = d.norm();
    if (len < 2.0) return;
    TriangleMesh& m = impl_->mesh;
    const size_t first = m.triangles.size();
    const double depth = veg_rng_.Uniform(0.6, 1.2), h = veg_rng_.Uniform(0.8, 1.8);
    const Eigen::Vector2d c = (a + b) / 2 + away * (depth / 2);
    m.AddBox(P3(c, Ground(c) + h / 2 - 0.05), Frame(d / len),
             Eigen::Vector3f(static_cast<float>(len / 2), static_cast<float>(depth / 2),
                             static_cast<float>(h / 2 + 0.05)),
             SurfaceClass::kFoliage, static_cast<float>(veg_rng_.Uniform(0.25, 0.45)));
    m.MarkVolume(first, static_cast<float>(o_.hedge_mean_free_path_m));
    ++num_hedges_;
  }

  void EmitPole(const Eigen::Vector2d& q, const Eigen::Vector2d& t,
                const Eigen::Vector2d& to_road) {
    TriangleMesh& m = impl_->mesh;
    const double z0 = Ground(q);
    const Eigen::Matrix3f R = Frame(t);
    if (rng_.Bernoulli(0.55)) {  // street lamp with an arm over the road
      const double h = rng_.Uniform(7.0, 9.0);
      m.AddCylinder(P3(q, z0 - 0.2), 0.1f, static_cast<float>(h + 0.2), 8, SurfaceClass::kPole,
                    0.45f);
      const Eigen::Vector2d mid = q + to_road * 0.9;
      Eigen::Matrix3f Ra = Frame(to_road);
      m.AddBox(P3(mid, z0 + h - 0.1), Ra, Eigen::Vector3f(0.9f, 0.05f, 0.05f), SurfaceClass::kPole,
               0.45f);
      m.AddBox(P3(q + to_road * 1.8, z0 + h - 0.2), Ra, Eigen::Vector3f(0.35f, 0.15f, 0.08f),
               SurfaceClass::kPole, 0.6f);
    } else {  // sign post; the plate faces the traffic
      const double h = rng_.Uniform(2.0, 2.6);
      m.AddCylinder(P3(q, z0 - 0.2), 0.04f, static_cast<float>(h + 0.2), 6, SurfaceClass::kPole,
                    0.45f);
      m.AddBox(P3(q, z0 + h + 0.3), R, Eigen::Vector3f(0.02f, 0.32f, 0.32f), SurfaceClass::kPole,
               0.92f);
    }
    ++impl_->stats.num_poles;
  }

  void EmitCar(const Eigen::Vector2d& c, const Eigen::Vector2d& t) {
    TriangleMesh& m = impl_->mesh;
    const double z0 = Ground(c);
    const Eigen::Matrix3f R = Frame(t);
    const double len = rng_.Uniform(3.9, 4.8), wid = rng_.Uniform(1.7, 1.85);
    const float paint = static_cast<float>(rng_.Uniform(0.1, 0.7));
    m.AddBox(P3(c, z0 + 0.67), R,
             Eigen::Vector3f(static_cast<float>(len / 2), static_cast<float>(wid / 2), 0.37f),
             SurfaceClass::kCar, paint);
    m.AddBox(
        P3(c - t * (0.1 * len), z0 + 1.28), R,
        Eigen::Vector3f(static_cast<float>(len * 0.28), static_cast<float>(wid / 2 - 0.08), 0.25f),
        SurfaceClass::kCar, 0.08f);
    const Eigen::Vector2d nrm(-t.y(), t.x());
    for (double sl : {-1.0, 1.0})
      for (double sw : {-1.0, 1.0})
        m.AddBox(P3(c + t * (sl * len * 0.32) + nrm * (sw * (wid / 2 - 0.12)), z0 + 0.31), R,
                 Eigen::Vector3f(0.31f, 0.11f, 0.31f), SurfaceClass::kCar, 0.05f);
    ++impl_->stats.num_cars;
  }

  void BuildObjects() {
    const auto& s = path().samples();
    for (int side : {1, -1}) {
      double next_lot = s.front().s + rng_.Uniform(0.0, 5.0);
      double next_pole = s.front().s + rng_.Uniform(0.0, o_.pole_spacing_m);
      double next_tree_block = s.front().s, tree_block_end = -1, next_tree = 0;
      double next_car_block = s.front().s, car_block_end = -1, next_car = 0;
      for (size_t i = 0; i < s.size(); ++i) {
        const PathSample& p = s[i];
        if (p.revisit) continue;  // objects of a revisited street exist already
        const Eigen::Vector2d nrm = Eigen::Vector2d(-p.tangent.y(), p.tangent.x()) * side;
        const double w = p.half_width, sw = p.sidewalk, front = w + sw;
        // Lots.
        if (p.s >= next_lot) {
          const double u = rng_.Uniform();
          double length;
          if (u < o_.building_probability) {
            length = rng_.Uniform(10.0, 32.0);
            const double setback = rng_.Bernoulli(0.7) ? 0.0 : rng_.Uniform(0.5, 3.0);
            const double hu = rng_.Uniform();
            const double height =
                o_.building_height_min_m +
                (o_.building_height_max_m - o_.building_height_min_m) * std::pow(hu, 1.5);
            if (!TryBuilding(p.p, p.tangent, nrm, front + 0.3 + setback, length,
                             rng_.Uniform(9.0, 20.0), height)) {
              length = 4.0;
            } else if (rng_.Bernoulli(0.5)) {  // a taller block behind, seen over and between
              TryBuilding(p.p, p.tangent, nrm, front + setback + rng_.Uniform(22.0, 30.0), length,
                          rng_.Uniform(10.0, 20.0), rng_.Uniform(10.0, 32.0));
            }
            if (rng_.Bernoulli(0.5)) length += rng_.Uniform(0.0, 1.0);
          } else if (u < o_.building_probability + 0.12) {  // gap or alley
            length = rng_.Uniform(3.0, 9.0);
            if (rng_.Bernoulli(0.5))
              TryBuilding(p.p, p.tangent, nrm, front + rng_.Uniform(15.0, 25.0), length + 6.0,
                          rng_.Uniform(10.0, 18.0), rng_.Uniform(8.0, 25.0));
          } else if (u < o_.building_probability + 0.24) {  // fenced yard with a house
            length = rng_.Uniform(10.0, 22.0);
            const Eigen::Vector2d a = p.p + nrm * (front + 0.25);
            const Eigen::Vector2d b = a + p.tangent * length;
            if (RectFree((a + b) / 2, p.tangent, length / 2, 0.1, 0.05)) {
              MarkRect((a + b) / 2, p.tangent, length / 2, 0.1);
              EmitFence(a, b);
              if (o_.volumetric_vegetation && veg_rng_.Bernoulli(o_.hedge_probability))
                EmitHedge(a + nrm * 0.15, b + nrm * 0.15, nrm);
            }
            TryBuilding(p.p + p.tangent * 2.0, p.tangent, nrm, front + rng_.Uniform(5.0, 9.0),
                        length - 4.0, rng_.Uniform(8.0, 12.0), rng_.Uniform(4.0, 9.0));
            if (rng_.Bernoulli(0.6)) {
              const Eigen::Vector2d q =
                  p.p + p.tangent * rng_.Uniform(2.0, length - 2.0) + nrm * (front + 2.5);
              if (PointFree(q, 0.5) && !Occupied(q)) {
                MarkFurniture(q, p.tangent, 0.5, 0.5);
                EmitTree(q);
              }
            }
          } else {  // open lot / parking
            length = rng_.Uniform(8.0, 25.0);
            if (o_.volumetric_vegetation && veg_rng_.Bernoulli(o_.hedge_probability)) {
              const Eigen::Vector2d a = p.p + nrm * (front + 0.4);
              if (PointFree(a + nrm * 0.5, 0.2) &&
                  PointFree(a + nrm * 0.5 + p.tangent * length, 0.2))
                EmitHedge(a, a + p.tangent * length, nrm);
            }
          }
          next_lot = p.s + length;
        }
        // Street lamps and sign posts at the curb.
        if (p.s >= next_pole) {
          const Eigen::Vector2d q = p.p + nrm * (w + 0.5);
          const PathNearest n = path().Nearest(q, 30.0);
          if (n.segment >= 0 && n.distance >= path().SampleOf(n).half_width + 0.3 && !Occupied(q)) {
            MarkFurniture(q, p.tangent, 0.3, 0.3);
            EmitPole(q, p.tangent, -nrm);
          }
          next_pole = p.s + o_.pole_spacing_m * rng_.Uniform(0.6, 1.4);
        }
        // Rows of trees on wide sidewalks (or just behind narrow ones).
        if (p.s >= next_tree_block) {
          if (rng_.Bernoulli(o_.tree_probability)) {
            tree_block_end = p.s + 60.0;
            next_tree = p.s + rng_.Uniform(0.0, 5.0);
          }
          next_tree_block = p.s + 60.0;
        }
        if (p.s < tree_block_end && p.s >= next_tree) {
          const double off = sw >= 2.5 ? w + sw * 0.55 : front + 1.5;
          const Eigen::Vector2d q = p.p + nrm * off;
          const PathNearest n = path().Nearest(q, 30.0);
          const bool on_road = n.segment >= 0 && n.distance < path().SampleOf(n).half_width + 0.6;
          if (!on_road && !Occupied(q)) {
            MarkFurniture(q, p.tangent, 0.8, 0.8);
            EmitTree(q);
          }
          next_tree = p.s + rng_.Uniform(7.0, 11.0);
        }
        // Rows of parked cars along the curb.
        if (p.s >= next_car_block) {
          if (rng_.Bernoulli(o_.parked_car_probability)) {
            car_block_end = p.s + 40.0;
            next_car = p.s;
          }
          next_car_block = p.s + 40.0;
        }
        if (p.s < car_block_end && p.s >= next_car) {
          const Eigen::Vector2d c = p.p + nrm * (w - 1.05);
          bool ok = rng_.Bernoulli(0.85);
          for (double a : {-2.3, 0.0, 2.3}) {
            for (double b : {-0.95, 0.95}) {
              if (!ok) break;
              const Eigen::Vector2d q = c + p.tangent * a + nrm * b;
              const PathNearest n = path().Nearest(q, 30.0);
              if (n.segment < 0 || n.distance < 2.4 ||
                  n.distance > path().SampleOf(n).half_width - 0.05)
                ok = false;
              if (Occupied(q)) ok = false;
            }
          }
          if (ok) {
            MarkFurniture(c, p.tangent, 2.3, 0.95);
            EmitCar(c, rng_.Bernoulli(0.8) ? p.tangent : Eigen::Vector2d(-p.tangent));
          }
          next_car = p.s + rng_.Uniform(5.4, 7.0);
        }
      }
    }
  }

  const std::vector<CityWorld::PathSpan>& spans_;
  bool either_direction_;
  CityWorld::Impl* impl_;
  const CityWorld::Options& o_;
  Rng rng_;
  Rng veg_rng_;  ///< Vegetation details only (the rest of the world does not depend on it).
  int num_hedges_ = 0;
  std::unordered_set<int64_t> occupied_, furniture_;
  bool check_furniture_ = false;
};

}  // namespace

Status GenerateCity(const std::vector<CityWorld::PathSpan>& spans, bool either_direction,
                    CityWorld::Impl* impl) {
  for (const CityWorld::PathSpan& span : spans) {
    if (span.trajectory->DurationSeconds() <= 0.0 || !(span.t_end_s > span.t_begin_s)) {
      return InvalidArgumentError("CityWorld::Build: the trajectory span is empty");
    }
  }
  Generator g(spans, either_direction, impl);
  return g.Run();
}

}  // namespace slam_mms::sim
