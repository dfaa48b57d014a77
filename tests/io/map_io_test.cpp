// PLY / PCD / LAS map files: round trips, foreign files, geo-referencing.
#include "slam_mms/io/map_io.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <GeographicLib/UTMUPS.hpp>
#include <cstring>
#include <fstream>
#include <random>

#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

MapCloud RandomMap(size_t n, bool normals, uint64_t seed, float extent = 500.0f) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-extent, extent);
  std::uniform_real_distribution<float> r(0.0f, 1.0f);
  MapCloud map;
  for (size_t i = 0; i < n; ++i) {
    map.cloud.Add(Eigen::Vector3f(u(rng), u(rng), 0.05f * u(rng)), r(rng));
    if (normals) map.normals.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized());
  }
  return map;
}

void ExpectSameMap(const MapCloud& a, const MapCloud& b) {
  ASSERT_EQ(a.cloud.size(), b.cloud.size());
  EXPECT_EQ(std::memcmp(a.cloud.points().data(), b.cloud.points().data(),
                        a.cloud.size() * sizeof(Eigen::Vector3f)),
            0);
  EXPECT_EQ(a.cloud.intensities(), b.cloud.intensities());
  ASSERT_EQ(a.normals.size(), b.normals.size());
  EXPECT_EQ(a.normals, b.normals);
}

class MapIoTest : public ::testing::Test {
 protected:
  void SetUp() override { tmp_ = testing::MakeTempDir("map_io"); }
  void TearDown() override { fs::remove_all(tmp_); }
  fs::path tmp_;
};

TEST_F(MapIoTest, PlyRoundTrip) {
  for (const bool normals : {false, true}) {
    const MapCloud map = RandomMap(5000, normals, 1);
    const fs::path file = tmp_ / "a.ply";
    ASSERT_TRUE(WritePly(map, file).ok());
    std::ifstream in(file, std::ios::binary);
    std::string header((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const size_t body = header.size() - (header.find("end_header\n") + 11);
    EXPECT_EQ(body, map.cloud.size() * (normals ? 28u : 16u));
    auto back = ReadPly(file);
    ASSERT_TRUE(back.ok()) << back.status().ToString();
    ExpectSameMap(map, *back);
  }
}

TEST_F(MapIoTest, PlyAsciiAndForeignTypes) {
  // CloudCompare-like ascii: double coordinates, uchar intensity, an extra property, a face
  // element.
  std::ofstream(tmp_ / "b.ply") << "ply\r\nformat ascii 1.0\r\ncomment foreign\r\n"
                                   "element vertex 3\r\nproperty double x\r\nproperty double y\r\n"
                                   "property double z\r\nproperty uchar red\r\n"
                                   "property float scalar_intensity\r\n"
                                   "element face 1\r\nproperty list uchar int vertex_indices\r\n"
                                   "end_header\r\n"
                                   "1.5 2.5 3.5 255 0.25\r\n-1 -2 -3 0 0.5\r\n0 0 1e3 7 1\r\n"
                                   "3 0 1 2\r\n";
  auto m = ReadPly(tmp_ / "b.ply");
  ASSERT_TRUE(m.ok()) << m.status().ToString();
  ASSERT_EQ(m->cloud.size(), 3u);
  EXPECT_EQ(m->cloud.points()[0], Eigen::Vector3f(1.5f, 2.5f, 3.5f));
  EXPECT_EQ(m->cloud.points()[2], Eigen::Vector3f(0.0f, 0.0f, 1000.0f));
  EXPECT_EQ(m->cloud.intensities()[1], 0.5f);
  EXPECT_FALSE(m->has_normals());

  // Big-endian binary with double x y z and int16 intensity.
  std::string body;
  const auto put_be = [&body](const void* p, size_t n) {
    const char* c = static_cast<const char*>(p);
    for (size_t i = 0; i < n; ++i) body += c[n - 1 - i];
  };
  for (int i = 0; i < 2; ++i) {
    const double xyz[3] = {1.0 + i, -2.0, 0.125};
    for (double v : xyz) put_be(&v, 8);
    const int16_t in = static_cast<int16_t>(-3 + i);
    put_be(&in, 2);
  }
  std::ofstream(tmp_ / "c.ply", std::ios::binary)
      << "ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty double x\n"
         "property double y\nproperty double z\nproperty short intensity\nend_header\n"
      << body;
  m = ReadPly(tmp_ / "c.ply");
  ASSERT_TRUE(m.ok()) << m.status().ToString();
  ASSERT_EQ(m->cloud.size(), 2u);
  EXPECT_EQ(m->cloud.points()[1], Eigen::Vector3f(2.0f, -2.0f, 0.125f));
  EXPECT_EQ(m->cloud.intensities()[0], -3.0f);
}

TEST_F(MapIoTest, PlyErrors) {
  const MapCloud map = RandomMap(100, true, 2);
  ASSERT_TRUE(WritePly(map, tmp_ / "a.ply").ok());
  fs::resize_file(tmp_ / "a.ply", fs::file_size(tmp_ / "a.ply") - 3);
  EXPECT_THAT(ReadPly(tmp_ / "a.ply").status().message(), HasSubstr("expected at least"));
  std::ofstream(tmp_ / "b.ply") << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                   "property float y\nproperty float z\nend_header\n1 2 3\n1 2\n";
  EXPECT_THAT(ReadPly(tmp_ / "b.ply").status().message(),
              HasSubstr("vertex has 2 values, expected 3"));
  std::ofstream(tmp_ / "c.ply") << "not a ply\n";
  EXPECT_THAT(ReadPly(tmp_ / "c.ply").status().message(), HasSubstr("not a PLY"));
  MapCloud bad = map;
  bad.normals.pop_back();
  EXPECT_EQ(WritePly(bad, tmp_ / "d.ply").code(), StatusCode::kInvalidArgument);
}

TEST_F(MapIoTest, PcdRoundTripAndAscii) {
  for (const bool normals : {false, true}) {
    const MapCloud map = RandomMap(3000, normals, 3);
    ASSERT_TRUE(WritePcd(map, tmp_ / "a.pcd").ok());
    auto back = ReadPcd(tmp_ / "a.pcd");
    ASSERT_TRUE(back.ok()) << back.status().ToString();
    ExpectSameMap(map, *back);
  }
  // PCL-style ascii with an rgb field, a padding field of count 3, curvature.
  std::ofstream(tmp_ / "b.pcd")
      << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb _ normal_x normal_y normal_z curvature\n"
         "SIZE 4 4 4 4 1 4 4 4 4\nTYPE F F F U U F F F F\nCOUNT 1 1 1 1 3 1 1 1 1\n"
         "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
         "1 2 3 4278190080 0 0 0 0 0 1 0.1\n-1 -2 -3 0 0 0 0 1 0 0 0.2\n";
  auto m = ReadPcd(tmp_ / "b.pcd");
  ASSERT_TRUE(m.ok()) << m.status().ToString();
  ASSERT_EQ(m->cloud.size(), 2u);
  EXPECT_EQ(m->cloud.points()[1], Eigen::Vector3f(-1, -2, -3));
  EXPECT_EQ(m->cloud.intensities()[0], 0.0f);
  ASSERT_TRUE(m->has_normals());
  EXPECT_EQ(m->normals[0], Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ(m->normals[1], Eigen::Vector3f(1, 0, 0));
  std::ofstream(tmp_ / "c.pcd") << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                                   "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary_compressed\n";
  EXPECT_EQ(ReadPcd(tmp_ / "c.pcd").status().code(), StatusCode::kUnimplemented);
  ASSERT_TRUE(WritePcd(RandomMap(10, false, 4), tmp_ / "d.pcd").ok());
  fs::resize_file(tmp_ / "d.pcd", fs::file_size(tmp_ / "d.pcd") - 1);
  EXPECT_THAT(ReadPcd(tmp_ / "d.pcd").status().message(), HasSubstr("binary data has"));
}

// Meridian arc length of WGS-84 from the equator to `lat_rad` by Simpson integration: an oracle for
// the UTM northing on a central meridian (northing = 0.9996 * arc), independent of GeographicLib.
double MeridianArc(double lat_rad) {
  const double a = 6378137.0, f = 1.0 / 298.257223563, e2 = f * (2 - f);
  const int n = 20000;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double phi = lat_rad * i / n;
    const double m = a * (1 - e2) / std::pow(1 - e2 * std::sin(phi) * std::sin(phi), 1.5);
    sum += m * (i == 0 || i == n ? 1 : (i % 2 ? 4 : 2));
  }
  return sum * lat_rad / n / 3.0;
}

TEST_F(MapIoTest, LasGeoReferencedRoundTrip) {
  const GeodeticPoint origin{49.013141872681, 8.4378138518088,
                             114.06644439697};  // KITTI 0013 start
  const MapCloud map = RandomMap(20000, false, 5, 2000.0f);
  const fs::path file = tmp_ / "map.las";
  ASSERT_TRUE(WriteLas(map, origin, file).ok());
  const std::string wkt = UtmZoneWkt(32, true);
  EXPECT_EQ(fs::file_size(file), 375u + 54u + wkt.size() + 1 + 30u * map.cloud.size());
  auto las = ReadLas(file);
  ASSERT_TRUE(las.ok()) << las.status().ToString();
  EXPECT_EQ(las->version_major, 1);
  EXPECT_EQ(las->version_minor, 4);
  EXPECT_EQ(las->point_format, 6);
  EXPECT_TRUE(las->global_encoding & (1 << 4));  // WKT
  EXPECT_EQ(las->wkt, wkt);
  EXPECT_THAT(las->wkt, HasSubstr("\"WGS 84 / UTM zone 32N\""));
  EXPECT_THAT(las->wkt, HasSubstr("AUTHORITY[\"EPSG\",\"32632\"]]"));
  EXPECT_THAT(las->wkt, HasSubstr("PARAMETER[\"central_meridian\",9]"));
  EXPECT_EQ(las->scale, Eigen::Vector3d::Constant(0.001));
  ASSERT_EQ(las->points_utm.size(), map.cloud.size());

  // Back to ENU through GeographicLib: within the 1 mm quantisation (+ float32 of the input).
  const GeographicLib::LocalCartesian enu(origin.latitude_deg, origin.longitude_deg,
                                          origin.height_m);
  Eigen::Vector3d lo = las->points_utm[0], hi = lo;
  double worst = 0.0;
  for (size_t i = 0; i < map.cloud.size(); ++i) {
    const Eigen::Vector3d& u = las->points_utm[i];
    lo = lo.cwiseMin(u);
    hi = hi.cwiseMax(u);
    double lat, lon, x, y, z;
    GeographicLib::UTMUPS::Reverse(32, true, u.x(), u.y(), lat, lon);
    enu.Forward(lat, lon, u.z(), x, y, z);
    worst = std::max(
        worst,
        (Eigen::Vector3d(x, y, z) - map.cloud.points()[i].cast<double>()).cwiseAbs().maxCoeff());
    EXPECT_EQ(las->intensities[i],
              static_cast<uint16_t>(std::lround(map.cloud.intensities()[i] * 65535.0)));
  }
  EXPECT_LT(worst, 0.0005 + 1e-4);
  EXPECT_LT((las->min - lo).norm(), 1e-9);
  EXPECT_LT((las->max - hi).norm(), 1e-9);
  // The origin's easting is in zone 32's band and its northing about 5.43e6 m.
  EXPECT_GT(lo.x(), 440000.0);
  EXPECT_LT(hi.x(), 470000.0);
  EXPECT_GT(lo.y(), 5425000.0);
  EXPECT_LT(hi.y(), 5433000.0);
}

TEST_F(MapIoTest, LasMatchesIndependentMeridianArc) {
  // A point on zone 32's central meridian (9 deg E) at 49 deg N, given in ENU about an origin near
  // it: UTM easting 500000, northing 0.9996 * meridian arc, height as given.
  const GeodeticPoint origin{48.999, 9.001, 100.0};
  const GeographicLib::LocalCartesian enu(origin.latitude_deg, origin.longitude_deg,
                                          origin.height_m);
  double x, y, z;
  enu.Forward(49.0, 9.0, 120.0, x, y, z);
  MapCloud map;
  map.cloud.Add(
      Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)), 0.5f);
  // float32 of an ENU coordinate about 150 m from the origin: ~8e-6 m.
  ASSERT_TRUE(WriteLas(map, origin, tmp_ / "m.las").ok());
  auto las = ReadLas(tmp_ / "m.las");
  ASSERT_TRUE(las.ok());
  const double northing = 0.9996 * MeridianArc(49.0 * M_PI / 180.0);
  EXPECT_NEAR(las->points_utm[0].x(), 500000.0, 0.001);
  EXPECT_NEAR(las->points_utm[0].y(), northing, 0.001);
  EXPECT_NEAR(las->points_utm[0].z(), 120.0, 0.001);
}

TEST_F(MapIoTest, LasSouthernHemisphereAndForcedZone) {
  const GeodeticPoint cape_town{-33.92, 18.42, 10.0};
  const MapCloud map = RandomMap(100, false, 6);
  ASSERT_TRUE(WriteLas(map, cape_town, tmp_ / "s.las").ok());
  auto las = ReadLas(tmp_ / "s.las");
  ASSERT_TRUE(las.ok());
  EXPECT_THAT(las->wkt, HasSubstr("UTM zone 34S"));
  EXPECT_THAT(las->wkt, HasSubstr("\"32734\""));
  EXPECT_THAT(las->wkt, HasSubstr("false_northing\",10000000"));
  EXPECT_GT(las->points_utm[0].y(), 6000000.0);
  // Forced neighbouring zone: same points, other easting.
  LasWriteOptions o;
  o.utm_zone = 33;
  o.north = false;
  ASSERT_TRUE(WriteLas(map, cape_town, tmp_ / "s33.las", o).ok());
  auto las33 = ReadLas(tmp_ / "s33.las");
  ASSERT_TRUE(las33.ok());
  EXPECT_THAT(las33->wkt, HasSubstr("UTM zone 33S"));
  double lat, lon, lat33, lon33;
  GeographicLib::UTMUPS::Reverse(34, false, las->points_utm[7].x(), las->points_utm[7].y(), lat,
                                 lon);
  GeographicLib::UTMUPS::Reverse(33, false, las33->points_utm[7].x(), las33->points_utm[7].y(),
                                 lat33, lon33);
  EXPECT_NEAR(lat, lat33, 2e-8);  // 2 mm
  EXPECT_NEAR(lon, lon33, 2e-8);
}

// Golden values from PROJ 9.1 (independent of GeographicLib): `projinfo EPSG:32632 -o WKT1_GDAL`
// and `echo "lat lon h" | cs2cs -f %.4f EPSG:4326 EPSG:326zz/327zz`.
TEST(UtmWktTest, MatchesProjWkt1Gdal) {
  EXPECT_EQ(UtmZoneWkt(32, true),
            "PROJCS[\"WGS 84 / UTM zone 32N\",GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID["
            "\"WGS 84\",6378137,298.257223563,AUTHORITY[\"EPSG\",\"7030\"]],AUTHORITY[\"EPSG\","
            "\"6326\"]],PRIMEM[\"Greenwich\",0,AUTHORITY[\"EPSG\",\"8901\"]],UNIT[\"degree\","
            "0.0174532925199433,AUTHORITY[\"EPSG\",\"9122\"]],AUTHORITY[\"EPSG\",\"4326\"]],"
            "PROJECTION[\"Transverse_Mercator\"],PARAMETER[\"latitude_of_origin\",0],PARAMETER["
            "\"central_meridian\",9],PARAMETER[\"scale_factor\",0.9996],PARAMETER[\"false_"
            "easting\",500000],PARAMETER[\"false_northing\",0],UNIT[\"metre\",1,AUTHORITY["
            "\"EPSG\",\"9001\"]],AXIS[\"Easting\",EAST],AXIS[\"Northing\",NORTH],AUTHORITY["
            "\"EPSG\",\"32632\"]]");
}

TEST_F(MapIoTest, LasOriginMatchesProj) {
  struct Case {
    GeodeticPoint origin;
    double easting, northing;
  };
  const Case cases[] = {
      {{49.013141872681, 8.4378138518088, 114.06644439697}, 458891.1966, 5429068.9448},
      {{-33.92, 18.42, 10.0}, 261488.8264, 6243716.3330}};
  for (const Case& c : cases) {
    MapCloud map;
    map.cloud.Add(Eigen::Vector3f::Zero(), 1.0f);
    ASSERT_TRUE(WriteLas(map, c.origin, tmp_ / "o.las").ok());
    auto las = ReadLas(tmp_ / "o.las");
    ASSERT_TRUE(las.ok());
    EXPECT_NEAR(las->points_utm[0].x(), c.easting, 0.0011);
    EXPECT_NEAR(las->points_utm[0].y(), c.northing, 0.0011);
    EXPECT_NEAR(las->points_utm[0].z(), c.origin.height_m, 0.0011);
    EXPECT_EQ(las->intensities[0], 65535);
  }
}

TEST_F(MapIoTest, LasErrors) {
  const MapCloud map = RandomMap(10, false, 7);
  EXPECT_EQ(WriteLas(map, GeodeticPoint{85.0, 0.0, 0.0}, tmp_ / "x.las").code(),
            StatusCode::kInvalidArgument);
  LasWriteOptions o;
  o.scale_m = 0.0;
  EXPECT_THAT(WriteLas(map, GeodeticPoint{49, 8, 0}, tmp_ / "x.las", o).message(),
              HasSubstr("LasWriteOptions::scale_m"));
  o = {};
  o.utm_zone = 61;
  EXPECT_THAT(o.Validate().message(), HasSubstr("utm_zone = 61"));
  ASSERT_TRUE(WriteLas(map, GeodeticPoint{49, 8, 0}, tmp_ / "t.las").ok());
  fs::resize_file(tmp_ / "t.las", fs::file_size(tmp_ / "t.las") - 1);
  EXPECT_THAT(ReadLas(tmp_ / "t.las").status().message(), HasSubstr("header says 10 points"));
  std::ofstream(tmp_ / "n.las") << "not a las file at all";
  EXPECT_EQ(ReadLas(tmp_ / "n.las").status().code(), StatusCode::kDataLoss);
}

TEST_F(MapIoTest, AFolderGivenAsAFileIsAnErrorNotAnException) {
  // An ifstream opens a folder and reports a size of 2^63: this threw std::length_error before.
  for (const auto& read : {ReadPly, ReadPcd}) {
    const StatusOr<MapCloud> r = read(tmp_);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
    EXPECT_THAT(r.status().message(), HasSubstr("is a folder"));
  }
  EXPECT_THAT(ReadLas(tmp_).status().message(), HasSubstr("is a folder"));
}

}  // namespace
}  // namespace slam_mms
