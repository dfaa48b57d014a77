// CityWorld: mesh helpers, the Embree scene and ray queries.
#include "slam_mms/sim/city_world.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "sim/city_world_impl.hpp"
#include "sim/random.hpp"

namespace slam_mms::sim {

const char* SurfaceClassName(SurfaceClass c) {
  switch (c) {
    case SurfaceClass::kRoad: return "road";
    case SurfaceClass::kMarking: return "marking";
    case SurfaceClass::kCurb: return "curb";
    case SurfaceClass::kSidewalk: return "sidewalk";
    case SurfaceClass::kTerrain: return "terrain";
    case SurfaceClass::kBuilding: return "building";
    case SurfaceClass::kPole: return "pole";
    case SurfaceClass::kTrunk: return "trunk";
    case SurfaceClass::kFoliage: return "foliage";
    case SurfaceClass::kCar: return "car";
    case SurfaceClass::kFence: return "fence";
    case SurfaceClass::kOther: return "other";
  }
  return "other";
}

void TriangleMesh::AddTriangle(const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                               const Eigen::Vector3f& c, SurfaceClass cls, float alb) {
  const int i = static_cast<int>(vertices.size());
  vertices.push_back(a);
  vertices.push_back(b);
  vertices.push_back(c);
  triangles.emplace_back(i, i + 1, i + 2);
  classes.push_back(cls);
  albedo.push_back(alb);
}

void TriangleMesh::AddBox(const Eigen::Vector3f& center, const Eigen::Matrix3f& R,
                          const Eigen::Vector3f& h, SurfaceClass cls, float alb) {
  const int base = static_cast<int>(vertices.size());
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3f s((k & 1) ? 1.f : -1.f, (k & 2) ? 1.f : -1.f, (k & 4) ? 1.f : -1.f);
    vertices.push_back(center + R * s.cwiseProduct(h));
  }
  static const int kFaces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                    {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                    {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& f : kFaces) {
    triangles.emplace_back(base + f[0], base + f[1], base + f[2]);
    classes.push_back(cls);
    albedo.push_back(alb);
  }
}

void TriangleMesh::AddCylinder(const Eigen::Vector3f& base, float radius, float height, int sides,
                               SurfaceClass cls, float alb) {
  const int b = static_cast<int>(vertices.size());
  for (int k = 0; k < sides; ++k) {
    const float a = 2.0f * static_cast<float>(M_PI) * k / sides;
    const Eigen::Vector3f o(radius * std::cos(a), radius * std::sin(a), 0.f);
    vertices.push_back(base + o);
    vertices.push_back(base + o + Eigen::Vector3f(0, 0, height));
  }
  const int top = static_cast<int>(vertices.size());
  vertices.push_back(base + Eigen::Vector3f(0, 0, height));
  for (int k = 0; k < sides; ++k) {
    const int k1 = (k + 1) % sides;
    triangles.emplace_back(b + 2 * k, b + 2 * k1, b + 2 * k + 1);
    triangles.emplace_back(b + 2 * k1, b + 2 * k1 + 1, b + 2 * k + 1);
    triangles.emplace_back(top, b + 2 * k + 1, b + 2 * k1 + 1);
    for (int r = 0; r < 3; ++r) {
      classes.push_back(cls);
      albedo.push_back(alb);
    }
  }
}

void TriangleMesh::MarkVolume(size_t first_triangle, float mfp) {
  mean_free_path_m.resize(triangles.size(), 0.f);
  for (size_t i = first_triangle; i < triangles.size(); ++i) mean_free_path_m[i] = mfp;
}

void TriangleMesh::Append(const TriangleMesh& o) {
  const int base = static_cast<int>(vertices.size());
  if (!mean_free_path_m.empty() || !o.mean_free_path_m.empty()) {
    mean_free_path_m.resize(triangles.size(), 0.f);
    if (o.mean_free_path_m.empty()) {
      mean_free_path_m.resize(triangles.size() + o.triangles.size(), 0.f);
    } else {
      mean_free_path_m.insert(mean_free_path_m.end(), o.mean_free_path_m.begin(),
                              o.mean_free_path_m.end());
    }
  }
  vertices.insert(vertices.end(), o.vertices.begin(), o.vertices.end());
  for (const auto& t : o.triangles) triangles.push_back(t + Eigen::Vector3i::Constant(base));
  classes.insert(classes.end(), o.classes.begin(), o.classes.end());
  albedo.insert(albedo.end(), o.albedo.begin(), o.albedo.end());
}

CityWorld::Impl::~Impl() {
  if (scene != nullptr) rtcReleaseScene(scene);
  if (device != nullptr) rtcReleaseDevice(device);
}

Status CityWorld::Impl::Commit() {
  if (mesh.triangles.empty()) return InvalidArgumentError("CityWorld: the mesh has no triangles");
  if (mesh.classes.size() != mesh.triangles.size() || mesh.albedo.size() != mesh.triangles.size()) {
    return InvalidArgumentError("CityWorld: classes/albedo must have one entry per triangle");
  }
  if (!mesh.mean_free_path_m.empty() && mesh.mean_free_path_m.size() != mesh.triangles.size()) {
    return InvalidArgumentError("CityWorld: mean_free_path_m must be empty or one per triangle");
  }
  texture.clear();
  if (options.road_roughness_rms_m > 0.0 || options.sidewalk_roughness_rms_m > 0.0 ||
      options.terrain_roughness_rms_m > 0.0) {
    // Lattice values uniform in [-sqrt(3), sqrt(3)] (unit variance), three octaves.
    texture.resize(3 * kTextureSize * kTextureSize);
    const uint64_t seed = MixSeed(options.seed, 0x7E47);
    for (size_t k = 0; k < texture.size(); ++k) {
      texture[k] = static_cast<float>(
          (static_cast<double>(MixSeed(seed, k) >> 11) * (1.0 / 9007199254740992.0) * 2.0 - 1.0) *
          std::sqrt(3.0));
    }
  }
  has_volumes = false;
  for (float m : mesh.mean_free_path_m) has_volumes = has_volumes || m > 0.f;
  for (const auto& t : mesh.triangles) {
    if (t.minCoeff() < 0 || t.maxCoeff() >= static_cast<int>(mesh.vertices.size())) {
      return InvalidArgumentError("CityWorld: a triangle indexes a missing vertex");
    }
  }
  device = rtcNewDevice("threads=1,set_affinity=0");
  if (device == nullptr) return UnavailableError("CityWorld: rtcNewDevice failed");
  scene = rtcNewScene(device);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertices.size()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0,
                                                            RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                                            mesh.triangles.size()));
  if (vb == nullptr || ib == nullptr)
    return InternalError("CityWorld: Embree buffer allocation failed");
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    vb[3 * i] = mesh.vertices[i].x();
    vb[3 * i + 1] = mesh.vertices[i].y();
    vb[3 * i + 2] = mesh.vertices[i].z();
  }
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) ib[3 * i + k] = static_cast<unsigned>(mesh.triangles[i](k));
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
    return InternalError("CityWorld: Embree scene build failed");
  }
  stats.num_triangles = mesh.triangles.size();
  return OkStatus();
}

float CityWorld::Impl::ShadeAlbedo(unsigned prim, float u, float v, SurfaceClass* cls) const {
  *cls = mesh.classes[prim];
  float a = mesh.albedo[prim];
  if (*cls == SurfaceClass::kRoad && prim < num_ground_triangles) {
    const Eigen::Vector3i& t = mesh.triangles[prim];
    const float w0 = 1.f - u - v;
    const float d = w0 * vertex_d[t(0)] + u * vertex_d[t(1)] + v * vertex_d[t(2)];
    const float s = w0 * vertex_s[t(0)] + u * vertex_s[t(1)] + v * vertex_s[t(2)];
    const float w = w0 * vertex_w[t(0)] + u * vertex_w[t(1)] + v * vertex_w[t(2)];
    // Solid edge lines 0.35-0.5 m inside the curb; dashed lines (3 m of 9 m) bounding the lane.
    const bool edge = d > w - 0.5f && d < w - 0.35f;
    const bool dash = d > 1.70f && d < 1.83f && std::fmod(std::fabs(s), 9.0f) < 3.0f && w > 4.0f;
    if (edge || dash) {
      *cls = SurfaceClass::kMarking;
      a = 0.85f;
    }
  }
  return a;
}

double CityWorld::Impl::GroundModelHeight(const Eigen::Vector2d& q, double* d_out,
                                          const PathSample** street) const {
  const PathNearest n = path.Nearest(q, 1e4);
  if (n.segment < 0) return 0.0;
  const PathSample& s = path.SampleOf(n);
  if (street != nullptr) *street = &s;
  if (d_out != nullptr) *d_out = n.distance;
  const double d = n.distance;
  // Cambered road (2 %), curb step, sidewalks rising 1 %, lots flat beyond.
  double z = path.ZRoad(n) - 0.02 * std::min(d, s.half_width);
  if (d > s.half_width) {
    z += options.curb_height_m + 0.01 * std::min(d - s.half_width, s.sidewalk);
  }
  return z;
}

Status CityWorld::Options::Validate() const {
  auto fail = [](const char* name, double v, const char* rule) {
    std::ostringstream s;
    s << "CityWorld::Options::" << name << " = " << v << "; " << rule;
    return InvalidArgumentError(s.str());
  };
  if (!(corridor_m >= 10.0)) return fail("corridor_m", corridor_m, "must be >= 10");
  if (!(ground_cell_m > 0.05 && ground_cell_m <= 2.0))
    return fail("ground_cell_m", ground_cell_m, "must be in (0.05, 2]");
  if (!(road_half_width_min_m >= 3.0))
    return fail("road_half_width_min_m", road_half_width_min_m, "must be >= 3");
  if (!(road_half_width_max_m >= road_half_width_min_m))
    return fail("road_half_width_max_m", road_half_width_max_m, "must be >= road_half_width_min_m");
  if (!(sidewalk_width_min_m >= 0.5))
    return fail("sidewalk_width_min_m", sidewalk_width_min_m, "must be >= 0.5");
  if (!(sidewalk_width_max_m >= sidewalk_width_min_m))
    return fail("sidewalk_width_max_m", sidewalk_width_max_m, "must be >= sidewalk_width_min_m");
  if (!(curb_height_m >= 0.0 && curb_height_m < 0.5))
    return fail("curb_height_m", curb_height_m, "must be in [0, 0.5)");
  if (!(building_height_min_m > 2.0))
    return fail("building_height_min_m", building_height_min_m, "must be > 2");
  if (!(building_height_max_m >= building_height_min_m))
    return fail("building_height_max_m", building_height_max_m, "must be >= building_height_min_m");
  for (auto [name, p] :
       {std::pair<const char*, double>{"building_probability", building_probability},
        {"tree_probability", tree_probability},
        {"parked_car_probability", parked_car_probability}}) {
    if (!(p >= 0.0 && p <= 1.0)) return fail(name, p, "must be in [0, 1]");
  }
  if (!(pole_spacing_m >= 5.0)) return fail("pole_spacing_m", pole_spacing_m, "must be >= 5");
  if (!(body_height_above_road_m > 0.0))
    return fail("body_height_above_road_m", body_height_above_road_m, "must be > 0");
  for (auto [name, r] :
       {std::pair<const char*, double>{"road_roughness_rms_m", road_roughness_rms_m},
        {"sidewalk_roughness_rms_m", sidewalk_roughness_rms_m},
        {"terrain_roughness_rms_m", terrain_roughness_rms_m}}) {
    if (!(r >= 0.0 && r <= 0.2)) return fail(name, r, "must be in [0, 0.2]");
  }
  if (!(foliage_mean_free_path_m > 0.01))
    return fail("foliage_mean_free_path_m", foliage_mean_free_path_m, "must be > 0.01");
  if (!(hedge_mean_free_path_m > 0.01))
    return fail("hedge_mean_free_path_m", hedge_mean_free_path_m, "must be > 0.01");
  if (!(hedge_probability >= 0.0 && hedge_probability <= 1.0))
    return fail("hedge_probability", hedge_probability, "must be in [0, 1]");
  return OkStatus();
}

void CityWorld::Options::EnableGroundRoughness() {
  road_roughness_rms_m = 0.005;
  sidewalk_roughness_rms_m = 0.008;
  terrain_roughness_rms_m = 0.03;
}

CityWorld::CityWorld(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
CityWorld::CityWorld(CityWorld&&) noexcept = default;
CityWorld& CityWorld::operator=(CityWorld&&) noexcept = default;
CityWorld::~CityWorld() = default;

StatusOr<CityWorld> CityWorld::Build(const ReferenceTrajectory& trajectory,
                                     const Options& options) {
  return Build(trajectory, options, trajectory.start_s(), trajectory.end_s());
}

StatusOr<CityWorld> CityWorld::Build(const ReferenceTrajectory& trajectory, const Options& options,
                                     double t_begin_s, double t_end_s) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (!(t_end_s > t_begin_s))
    return InvalidArgumentError("CityWorld::Build: t_end_s must be > t_begin_s");
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  const PathSpan span{&trajectory, std::max(t_begin_s, trajectory.start_s()),
                      std::min(t_end_s, trajectory.end_s())};
  SLAM_MMS_RETURN_IF_ERROR(GenerateCity({span}, /*either_direction=*/false, impl.get()));
  SLAM_MMS_RETURN_IF_ERROR(impl->Commit());
  return CityWorld(std::move(impl));
}

StatusOr<CityWorld> CityWorld::Build(const std::vector<PathSpan>& paths, const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (paths.empty()) return InvalidArgumentError("CityWorld::Build: no paths");
  std::vector<PathSpan> clamped;
  for (size_t i = 0; i < paths.size(); ++i) {
    const PathSpan& p = paths[i];
    if (p.trajectory == nullptr)
      return InvalidArgumentError("CityWorld::Build: paths[" + std::to_string(i) +
                                  "].trajectory is null");
    if (!(p.t_end_s > p.t_begin_s))
      return InvalidArgumentError("CityWorld::Build: paths[" + std::to_string(i) +
                                  "]: t_end_s must be > t_begin_s");
    clamped.push_back({p.trajectory, std::max(p.t_begin_s, p.trajectory->start_s()),
                       std::min(p.t_end_s, p.trajectory->end_s())});
  }
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  SLAM_MMS_RETURN_IF_ERROR(GenerateCity(clamped, /*either_direction=*/true, impl.get()));
  SLAM_MMS_RETURN_IF_ERROR(impl->Commit());
  return CityWorld(std::move(impl));
}

StatusOr<CityWorld> CityWorld::FromMesh(TriangleMesh mesh) {
  return FromMesh(std::move(mesh), Options());
}

StatusOr<CityWorld> CityWorld::FromMesh(TriangleMesh mesh, const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->mesh = std::move(mesh);
  SLAM_MMS_RETURN_IF_ERROR(impl->Commit());
  return CityWorld(std::move(impl));
}

void CityWorld::Intersect(const Eigen::Vector3f* origins, const Eigen::Vector3f* directions,
                          size_t n, float min_range_m, float max_range_m, RayHit* hits) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  alignas(64) RTCRayHit16 rh;
  alignas(64) int valid[16];
  for (size_t start = 0; start < n; start += 16) {
    const size_t m = std::min<size_t>(16, n - start);
    for (size_t k = 0; k < 16; ++k) {
      const size_t i = start + std::min(k, m - 1);
      valid[k] = k < m ? -1 : 0;
      rh.ray.org_x[k] = origins[i].x();
      rh.ray.org_y[k] = origins[i].y();
      rh.ray.org_z[k] = origins[i].z();
      rh.ray.dir_x[k] = directions[i].x();
      rh.ray.dir_y[k] = directions[i].y();
      rh.ray.dir_z[k] = directions[i].z();
      rh.ray.tnear[k] = min_range_m;
      rh.ray.tfar[k] = max_range_m;
      rh.ray.time[k] = 0.f;
      rh.ray.mask[k] = 0xFFFFFFFFu;
      rh.ray.id[k] = static_cast<unsigned>(k);
      rh.ray.flags[k] = 0;
      rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect16(valid, impl_->scene, &context, &rh);
    for (size_t k = 0; k < m; ++k) {
      RayHit& h = hits[start + k];
      if (rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) {
        h = RayHit{};
        continue;
      }
      impl_->FinishHit(origins[start + k], directions[start + k], rh.ray.tfar[k], rh.hit.primID[k],
                       rh.hit.u[k], rh.hit.v[k],
                       Eigen::Vector3f(rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]), &h);
    }
  }
}

void CityWorld::Impl::FinishHit(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t,
                                unsigned prim, float u, float v, Eigen::Vector3f ng,
                                RayHit* h) const {
  *h = RayHit{};
  h->range_m = t;
  const float len = ng.norm();
  ng = len > 0 ? Eigen::Vector3f(ng / len) : Eigen::Vector3f::UnitZ();
  if (ng.dot(d) > 0.f) ng = -ng;
  h->normal_world = ng;
  h->albedo = ShadeAlbedo(prim, u, v, &h->surface);
  if (has_volumes && mesh.mean_free_path_m[prim] > 0.f) {
    // Hull faces are wound outward: (b - a) x (c - a) points out of the volume.
    const Eigen::Vector3i& tri = mesh.triangles[prim];
    const Eigen::Vector3f& a = mesh.vertices[tri(0)];
    const Eigen::Vector3f n_out = (mesh.vertices[tri(1)] - a).cross(mesh.vertices[tri(2)] - a);
    h->mean_free_path_m = mesh.mean_free_path_m[prim];
    h->entering = n_out.dot(d) < 0.f;
    return;
  }
  const double rms = RoughnessRms(h->surface);
  if (rms > 0.0) {
    // Surface displaced by height z(p) along its normal: the ray meets it dr = -z / |cos| from
    // the flat hit (two fixed-point steps on z at the moved point, clamped at grazing angles).
    const double cos_inc = std::max(0.05, static_cast<double>(std::abs(ng.dot(d))));
    const Eigen::Vector3d p0 = (o + d * t).cast<double>(), dd = d.cast<double>();
    double dr = 0.0;
    for (int it = 0; it < 2; ++it) {
      const Eigen::Vector3d p = p0 + dd * dr;
      dr = -rms * Texture(p.x(), p.y()) / cos_inc;
    }
    h->range_m = std::max(1e-3f, static_cast<float>(t + dr));
  }
}

RayHit CityWorld::Impl::IntersectOne(const Eigen::Vector3f& o, const Eigen::Vector3f& d,
                                     float tnear, float tfar) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  rh.ray.org_x = o.x();
  rh.ray.org_y = o.y();
  rh.ray.org_z = o.z();
  rh.ray.dir_x = d.x();
  rh.ray.dir_y = d.y();
  rh.ray.dir_z = d.z();
  rh.ray.tnear = tnear;
  rh.ray.tfar = tfar;
  rh.ray.time = 0.f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene, &context, &rh);
  RayHit h;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
  FinishHit(o, d, rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v,
            Eigen::Vector3f(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z), &h);
  return h;
}

namespace {

double KeyUniform(uint64_t key, uint64_t stream) {
  return (static_cast<double>(MixSeed(key, stream) >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

}  // namespace

double CityWorld::Impl::Texture(double x, double y) const {
  // Octaves of smoothstep-interpolated value noise, lattice 0.4 / 0.2 / 0.1 m, each from its own
  // table of kTextureSize^2 lattice values (periods of 102, 51 and 26 m, never aligned). With
  // independent unit-variance lattice values the interpolated variance averages (26/35)^2.
  static constexpr double kCell[3] = {0.4, 0.2, 0.1};
  static constexpr double kAmp[3] = {1.0, 0.6, 0.35};
  static const double norm = (26.0 / 35.0) * std::sqrt(1.0 + 0.36 + 0.1225);
  constexpr int64_t kMask = kTextureSize - 1;
  double z = 0.0;
  for (int oct = 0; oct < 3; ++oct) {
    const float* table = texture.data() + oct * kTextureSize * kTextureSize;
    const double gx = x / kCell[oct], gy = y / kCell[oct];
    const double fx = std::floor(gx), fy = std::floor(gy);
    const int64_t i = static_cast<int64_t>(fx), j = static_cast<int64_t>(fy);
    double tx = gx - fx, ty = gy - fy;
    tx = tx * tx * (3.0 - 2.0 * tx);
    ty = ty * ty * (3.0 - 2.0 * ty);
    const int64_t i0 = i & kMask, i1 = (i + 1) & kMask;
    const int64_t j0 = (j & kMask) * kTextureSize, j1 = ((j + 1) & kMask) * kTextureSize;
    const double v00 = table[j0 + i0], v10 = table[j0 + i1];
    const double v01 = table[j1 + i0], v11 = table[j1 + i1];
    z += kAmp[oct] * ((v00 * (1 - tx) + v10 * tx) * (1 - ty) + (v01 * (1 - tx) + v11 * tx) * ty);
  }
  return z / norm;
}

double CityWorld::Impl::RoughnessRms(SurfaceClass cls) const {
  switch (cls) {
    case SurfaceClass::kRoad:
    case SurfaceClass::kMarking: return options.road_roughness_rms_m;
    case SurfaceClass::kCurb:
    case SurfaceClass::kSidewalk: return options.sidewalk_roughness_rms_m;
    case SurfaceClass::kTerrain: return options.terrain_roughness_rms_m;
    default: return 0.0;
  }
}

double CityWorld::RoughnessHeight(double x, double y, SurfaceClass cls) const {
  const double rms = impl_->RoughnessRms(cls);
  return rms > 0.0 ? rms * impl_->Texture(x, y) : 0.0;
}

void CityWorld::IntersectScattering(const Eigen::Vector3f* origins,
                                    const Eigen::Vector3f* directions, const uint64_t* keys,
                                    size_t n, float min_range_m, float max_range_m,
                                    RayHit* hits) const {
  Intersect(origins, directions, n, min_range_m, max_range_m, hits);
  if (!impl_->has_volumes) return;
  for (size_t i = 0; i < n; ++i) {
    if (hits[i].mean_free_path_m <= 0.f) continue;
    const Eigen::Vector3f& o = origins[i];
    const Eigen::Vector3f& d = directions[i];
    RayHit h = hits[i];
    bool resolved = false;
    // Walk the hull faces along the ray: entering one, the penetration depth is exponential
    // (Beer-Lambert); a return there, unless the next face or a solid surface comes first.
    for (int step = 0; step < 16 && h.range_m >= 0.f && h.mean_free_path_m > 0.f; ++step) {
      const RayHit next = impl_->IntersectOne(o, d, h.range_m + 1e-4f, max_range_m);
      if (h.entering) {
        const double depth = -h.mean_free_path_m * std::log(KeyUniform(keys[i], 2 * step));
        if (next.range_m < 0.f || h.range_m + depth < next.range_m) {
          const double r = h.range_m + depth;
          if (r > max_range_m) {
            h = RayHit{};
            resolved = true;
            break;
          }
          // Leaves at random orientation: |cos incidence| uniform in (0, 1].
          const double c = KeyUniform(keys[i], 2 * step + 1);
          const Eigen::Vector3f axis =
              std::abs(d.z()) < 0.9f ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f::UnitX();
          const Eigen::Vector3f perp = d.cross(axis).normalized();
          RayHit v;
          v.range_m = static_cast<float>(r);
          v.normal_world = (-d * static_cast<float>(c) +
                            perp * static_cast<float>(std::sqrt(std::max(0.0, 1.0 - c * c))));
          v.surface = h.surface;
          v.albedo = h.albedo;
          v.volume_return = true;
          h = v;
          resolved = true;
          break;
        }
      }
      h = next;
    }
    if (!resolved && h.mean_free_path_m > 0.f) h = RayHit{};  // gave up inside a tangle of hulls
    hits[i] = h;
  }
}

double CityWorld::SkyBlockage(const Eigen::Vector3d& p_world, int num_rays,
                              double min_elevation_deg) const {
  if (num_rays <= 0) return 0.0;
  std::vector<Eigen::Vector3f> o(num_rays, p_world.cast<float>()), d(num_rays);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  const double s0 = std::sin(min_elevation_deg * M_PI / 180.0);
  for (int i = 0; i < num_rays; ++i) {
    const double sz = s0 + (1.0 - s0) * (i + 0.5) / num_rays;  // uniform in solid angle
    const double r = std::sqrt(std::max(0.0, 1.0 - sz * sz));
    const double az = golden * i;
    d[i] = Eigen::Vector3f(static_cast<float>(r * std::cos(az)),
                           static_cast<float>(r * std::sin(az)), static_cast<float>(sz));
  }
  std::vector<RayHit> h(num_rays);
  Intersect(o.data(), d.data(), num_rays, 0.05f, 300.f, h.data());
  int blocked = 0;
  for (const auto& x : h) blocked += x.range_m > 0 ? 1 : 0;
  return static_cast<double>(blocked) / num_rays;
}

double CityWorld::GroundHeight(double x, double y) const {
  if (!impl_->has_path) return 0.0;
  return impl_->GroundModelHeight(Eigen::Vector2d(x, y), nullptr, nullptr);
}

const TriangleMesh& CityWorld::mesh() const { return impl_->mesh; }
const CityWorld::Stats& CityWorld::stats() const { return impl_->stats; }

}  // namespace slam_mms::sim
