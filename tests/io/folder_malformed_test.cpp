// Bad drive folders: a good folder written from a synthetic KITTI drive (WriteDriveFolder), then
// damaged one way per test. Each case checks the code and that the message names the file, the
// line and the field (issue 21's list: truncated PCD, wrong header counts, unknown DATA, PLY
// without vertex, CSV field count / non-number / backwards / header, NMEA checksum and date,
// scans.csv naming a missing file, extrinsics that are not a rotation or have 15 numbers).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

#include "io/folder_test_util.hpp"
#include "slam_mms/io/drive_folder_writer.hpp"
#include "slam_mms/io/folder_drive_reader.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

constexpr const char* kPcdHeader =
    "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\n"
    "COUNT 1 1 1 1\nWIDTH 4\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ";

class FolderMalformedTest : public ::testing::Test {
 protected:
  void SetUp() override {
    tmp_ = testing::MakeTempDir("folder_malformed");
    const fs::path drive = testing::WriteSyntheticKittiDrive(tmp_, 3, 200);
    auto kitti = KittiDriveReader::Open(drive, KittiRawReader::Options());
    ASSERT_TRUE(kitti.ok()) << kitti.status().ToString();
    dir_ = tmp_ / "folder";
    ASSERT_TRUE(WriteDriveFolder(**kitti, dir_, FolderWriteOptions()).ok());
    ASSERT_TRUE(FolderDriveReader::Open(dir_, {}).ok());
  }
  void TearDown() override { fs::remove_all(tmp_); }

  Status OpenStatus(const FolderDriveReader::Options& o = {}) {
    return FolderDriveReader::Open(dir_, o).status();
  }
  // Replaces scan 1 with `bytes` (as `name` in scans.csv) and reads it.
  Status ReadReplacedScan(const std::string& name, const std::string& bytes) {
    testing::WriteFile(dir_ / "scans" / name, bytes);
    std::string csv = testing::ReadFile(dir_ / "scans.csv");
    csv.replace(csv.find(scan1_name_), scan1_name_.size(), name);
    scan1_name_ = name;
    testing::WriteFile(dir_ / "scans.csv", csv);
    auto reader = FolderDriveReader::Open(dir_, {});
    if (!reader.ok()) return reader.status();
    auto scan = (*reader)->ReadScan(1);
    return scan.ok() ? OkStatus() : scan.status();
  }
  // Replaces line `line` (1-based) of `file` by `text`.
  void ReplaceLine(const std::string& file, int line, const std::string& text) {
    std::string s = testing::ReadFile(dir_ / file);
    size_t a = 0;
    for (int k = 1; k < line; ++k) a = s.find('\n', a) + 1;
    const size_t b = s.find('\n', a);
    s.replace(a, b - a, text);
    testing::WriteFile(dir_ / file, s);
  }
  std::string Line(const std::string& file, int line) {
    const std::string s = testing::ReadFile(dir_ / file);
    size_t a = 0;
    for (int k = 1; k < line; ++k) a = s.find('\n', a) + 1;
    return s.substr(a, s.find('\n', a) - a);
  }
  std::string Path(const std::string& name) { return (dir_ / name).string(); }

  fs::path tmp_, dir_;
  std::string scan1_name_ = "0000000001.pcd";
};

// ---- Scan files ----------------------------------------------------------------------------
TEST_F(FolderMalformedTest, TruncatedPcd) {
  const fs::path f = dir_ / "scans" / "0000000001.pcd";
  fs::resize_file(f, fs::file_size(f) - 20);  // 202 points declared, 200 complete
  auto reader = FolderDriveReader::Open(dir_, {});
  ASSERT_TRUE(reader.ok());
  const Status s = (*reader)->ReadScan(1).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(f.string()), HasSubstr("only 200 of 202 points"),
                                 HasSubstr("expected at least")));
  EXPECT_TRUE((*reader)->ReadScan(0).ok());  // the other scans stay readable
  // Ascii: fewer lines than POINTS.
  const Status a = ReadReplacedScan("a.pcd", std::string(kPcdHeader) + "ascii\n1 2 3 4\n5 6 7 8\n");
  EXPECT_EQ(a.code(), StatusCode::kDataLoss);
  EXPECT_THAT(a.message(), AllOf(HasSubstr("a.pcd"), HasSubstr("ends after 2 of 4 points")));
}

TEST_F(FolderMalformedTest, PcdWrongHeaderCounts) {
  Status s = ReadReplacedScan("a.pcd",
                              "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4\nTYPE F F F F\n"
                              "POINTS 1\nDATA ascii\n1 2 3 4\n");
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(),
              AllOf(HasSubstr("a.pcd:3: SIZE has 3 entries but FIELDS (line 2) has 4")));
  s = ReadReplacedScan("b.pcd",
                       "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 5\nHEIGHT 2\nPOINTS 9\n"
                       "DATA ascii\n");
  EXPECT_THAT(s.message(), HasSubstr("b.pcd:6: POINTS 9 but WIDTH x HEIGHT = 5 x 2"));
  s = ReadReplacedScan("c.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F X\nPOINTS 1\nDATA ascii\n");
  EXPECT_THAT(s.message(), HasSubstr("c.pcd:3: field 'z' has TYPE X SIZE 4"));
  s = ReadReplacedScan("d.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS many\nDATA ascii\n");
  EXPECT_THAT(s.message(), HasSubstr("d.pcd:4: POINTS entry 1 'many' is not a non-negative"));
  s = ReadReplacedScan("e.pcd",
                       "FIELDS x y intensity\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\n"
                       "DATA ascii\n1 2 3\n");
  EXPECT_THAT(s.message(), AllOf(HasSubstr("e.pcd"), HasSubstr("has no field 'z'")));
  s = ReadReplacedScan("f.pcd", std::string(kPcdHeader) + "ascii\n1 2 3 4\n5 6 x 8\n");
  EXPECT_THAT(s.message(), HasSubstr("f.pcd:13: point 1 field 'z': 'x' is not a number"));
  s = ReadReplacedScan("g.pcd", std::string(kPcdHeader) + "ascii\n1 2 3 4\n5 6 7\n");
  EXPECT_THAT(s.message(), HasSubstr("g.pcd:13: point has 3 values, expected 4"));
}

TEST_F(FolderMalformedTest, PcdUnknownAndCompressedData) {
  Status s = ReadReplacedScan("a.pcd", std::string(kPcdHeader) + "binary_packed\n");
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("a.pcd:11: unknown PCD DATA 'binary_packed'"));
  s = ReadReplacedScan("b.pcd", std::string(kPcdHeader) + "binary_compressed\n");
  EXPECT_EQ(s.code(), StatusCode::kUnimplemented);
  EXPECT_THAT(s.message(), HasSubstr("b.pcd:11: PCD DATA binary_compressed is not supported"));
  s = ReadReplacedScan("c.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\n");
  EXPECT_THAT(s.message(), HasSubstr("c.pcd: PCD header has no DATA line"));
}

TEST_F(FolderMalformedTest, PlyWithoutVertexElementAndTruncated) {
  Status s = ReadReplacedScan("a.ply",
                              "ply\nformat ascii 1.0\nelement face 1\n"
                              "property list uchar int vertex_indices\nend_header\n3 0 1 2\n");
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("a.ply: PLY header has no 'vertex' element"));
  s = ReadReplacedScan("b.ply",
                       "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                       "property float y\nproperty float z\nend_header\n" +
                           std::string(24, '\0'));
  EXPECT_THAT(s.message(), AllOf(HasSubstr("b.ply: PLY binary data has 24 bytes"),
                                 HasSubstr("only 2 of 3 vertices")));
  s = ReadReplacedScan("c.ply",
                       "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
                       "property float128 x\nend_header\n");
  EXPECT_THAT(s.message(), HasSubstr("c.ply:4: bad property line"));
}

TEST_F(FolderMalformedTest, BadTimeFieldEmptyScanAndBin) {
  // A time field in nanoseconds is not silently taken as seconds.
  Status s = ReadReplacedScan("a.pcd",
                              "FIELDS x y z t\nSIZE 4 4 4 4\nTYPE F F F U\nPOINTS 2\nDATA ascii\n"
                              "1 2 3 0\n4 5 6 50000000\n");
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(),
              AllOf(HasSubstr("a.pcd: point 1 field 't'"), HasSubstr("seconds from the scan")));
  s = ReadReplacedScan("b.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 0\nDATA binary\n");
  EXPECT_THAT(s.message(), HasSubstr("b.pcd: scan contains no points"));
  s = ReadReplacedScan("c.bin", std::string(17, '\0'));
  EXPECT_THAT(s.message(), AllOf(HasSubstr("c.bin: size 17 bytes is not a multiple of 16")));
}

// ---- scans.csv -------------------------------------------------------------------------------
TEST_F(FolderMalformedTest, ScansCsvMissingFileAndBadRows) {
  const std::string good = testing::ReadFile(dir_ / "scans.csv");
  ReplaceLine("scans.csv", 3, "missing.pcd,1317042651210000000,1317042651310000000");
  Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_THAT(s.message(),
              AllOf(HasSubstr(Path("scans.csv") + ":3: field 'file': "),
                    HasSubstr((dir_ / "scans" / "missing.pcd").string() + " not found")));
  testing::WriteFile(dir_ / "scans.csv", good);
  const std::string line3 = Line("scans.csv", 3);
  const std::string stamps = line3.substr(line3.find(','));
  ReplaceLine("scans.csv", 3, "0000000001.txt" + stamps);
  EXPECT_THAT(OpenStatus().message(),
              HasSubstr(Path("scans.csv") + ":3: field 'file': '0000000001.txt' has an unknown"));
  ReplaceLine("scans.csv", 3, "0000000000.pcd" + stamps);
  EXPECT_THAT(OpenStatus().message(), HasSubstr(":3: field 'file': '0000000000.pcd' already listed "
                                                "on line 2"));
  ReplaceLine("scans.csv", 3, "0000000001.pcd,1317042651306324297,1317042651306324297");
  EXPECT_THAT(OpenStatus().message(),
              HasSubstr(":3: field 'stamp_end_ns': 1317042651306324297 not after stamp_start_ns"));
  ReplaceLine("scans.csv", 3, "0000000001.pcd,1317042651006324297,1317042651106324297");
  EXPECT_THAT(OpenStatus().message(),
              AllOf(HasSubstr(":3: field 'stamp_start_ns': 1317042651006324297 goes backwards "
                              "(line 2 has")));
  ReplaceLine("scans.csv", 3, "0000000001.pcd,1.3e18,1317042651106324297");
  EXPECT_THAT(OpenStatus().message(),
              HasSubstr(":3: field 'stamp_start_ns': '1.3e18' is not an integer"));
  ReplaceLine("scans.csv", 3, "../../etc/passwd.bin,1,2");
  EXPECT_THAT(OpenStatus().message(), HasSubstr("must be a name relative to scans/"));
}

// ---- CSV streams -------------------------------------------------------------------------------
TEST_F(FolderMalformedTest, ImuCsvFieldCountNumberBackwardsHeader) {
  const std::string good = testing::ReadFile(dir_ / "imu.csv");
  const std::string row = Line("imu.csv", 3);
  ReplaceLine("imu.csv", 3, row.substr(0, row.rfind(',')));
  Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(Path("imu.csv") + ":3: 6 fields, expected 7"),
                                 HasSubstr("field 'wz' is missing")));
  ReplaceLine("imu.csv", 3, row + ",7");
  EXPECT_THAT(OpenStatus().message(), HasSubstr(":3: 8 fields, expected 7 (header on line 1); "
                                                "extra field '7' after 'wz'"));
  std::vector<std::string> f;
  std::stringstream fields(row);
  for (std::string v; std::getline(fields, v, ',');) f.push_back(v);
  ASSERT_EQ(f.size(), 7u);
  ReplaceLine("imu.csv", 3,
              f[0] + "," + f[1] + ",abc," + f[3] + "," + f[4] + "," + f[5] + "," + f[6]);
  EXPECT_THAT(OpenStatus().message(),
              HasSubstr(Path("imu.csv") + ":3: field 'ay': 'abc' is not a number"));
  ReplaceLine("imu.csv", 3,
              f[0] + "," + f[1] + "," + f[2] + ",inf," + f[4] + "," + f[5] + "," + f[6]);
  EXPECT_THAT(OpenStatus().message(), HasSubstr(":3: field 'az': 'inf' is not finite"));
  // Time going backwards / duplicated: row 3 gets row 2's stamp.
  const std::string row2 = Line("imu.csv", 2);
  ReplaceLine("imu.csv", 3, row2);
  EXPECT_THAT(OpenStatus().message(), AllOf(HasSubstr(Path("imu.csv") + ":3: field 'stamp_ns': "),
                                            HasSubstr(" duplicated (line 2 has ")));
  ReplaceLine("imu.csv", 3, "1" + row2.substr(row2.find(',')));
  EXPECT_THAT(OpenStatus().message(), HasSubstr(":3: field 'stamp_ns': 1 goes backwards"));
  // Wrong header: columns swapped, unknown, missing.
  testing::WriteFile(dir_ / "imu.csv", good);
  ReplaceLine("imu.csv", 1, "stamp_ns,ay,ax,az,wx,wy,wz");
  EXPECT_THAT(OpenStatus().message(),
              HasSubstr(Path("imu.csv") + ":1: header column 2 is 'ay', expected 'ax'"));
  ReplaceLine("imu.csv", 1, "stamp_ns,ax,ay,az,wx,wy,wz,temp");
  EXPECT_THAT(OpenStatus().message(),
              HasSubstr(":1: header column 8 'temp' is unknown or out of order"));
  ReplaceLine("imu.csv", 1, "stamp_ns,ax,ay,az,wx,wy");
  EXPECT_THAT(OpenStatus().message(), HasSubstr(":1: header has 6 columns; column 7 'wz' is "
                                                "missing"));
  testing::WriteFile(dir_ / "imu.csv", "# only a comment\n\n");
  EXPECT_THAT(OpenStatus().message(), HasSubstr(Path("imu.csv") + ": no header line"));
  fs::remove(dir_ / "imu.csv");
  EXPECT_EQ(OpenStatus().code(), StatusCode::kNotFound);
  EXPECT_THAT(OpenStatus().message(), HasSubstr("required unless pos.csv"));
}

TEST_F(FolderMalformedTest, GnssAndInitialStateCsv) {
  const std::string row = Line("gnss.csv", 2);
  ReplaceLine("gnss.csv", 2, row.substr(0, row.rfind(',', row.rfind(',') - 1)) + ",rtk,8");
  EXPECT_THAT(OpenStatus().message(),
              HasSubstr(Path("gnss.csv") + ":2: field 'fix': 'rtk' is not one of none, sps"));
  ReplaceLine("gnss.csv", 2, "1317042651106324297,91,8,100,1,1,1,sps");
  EXPECT_THAT(OpenStatus().message(), HasSubstr(":2: 8 fields, expected 9"));
  ReplaceLine("gnss.csv", 2, "1317042651106324297,91,8,100,1,1,1,sps,5");
  EXPECT_THAT(OpenStatus().message(), HasSubstr(":2: field 'lat_deg': 91 outside [-90, 90]"));
  ReplaceLine("gnss.csv", 2, "1317042651106324297,49,8,100,-1,1,1,sps,5");
  EXPECT_THAT(OpenStatus().message(), HasSubstr(":2: field 'sigma_e_m': -1 is negative"));
  // The KITTI source states its attitude's accuracy: the three sigma columns are written.
  EXPECT_EQ(Line("initial_state.csv", 1),
            "stamp_ns,roll_deg,pitch_deg,yaw_deg,v_east_mps,v_north_mps,v_up_mps,sigma_roll_deg,"
            "sigma_pitch_deg,sigma_yaw_deg");
  ReplaceLine("initial_state.csv", 2, "1317042651106324297,0,0,x,0,0,0,0.03,0.03,0.1");
  EXPECT_THAT(OpenStatus().message(), HasSubstr(Path("gnss.csv") + ":2"));  // gnss comes first
  fs::remove(dir_ / "gnss.csv");
  EXPECT_THAT(OpenStatus().message(),
              HasSubstr(Path("initial_state.csv") + ":2: field 'yaw_deg': 'x' is not a number"));
  ReplaceLine("initial_state.csv", 2, "1317042651106324297,0,0,0,0,0,0,0.03,-0.03,0.1");
  EXPECT_THAT(OpenStatus().message(),
              HasSubstr(Path("initial_state.csv") + ":2: field 'sigma_pitch_deg': -0.0"));
  EXPECT_THAT(OpenStatus().message(), HasSubstr("outside [1"));
  ReplaceLine("initial_state.csv", 1,
              "stamp_ns,roll_deg,pitch_deg,yaw_deg,v_east_mps,v_north_mps,v_up_mps,sigma_roll_deg");
  ReplaceLine("initial_state.csv", 2, "1317042651106324297,0,0,0,0,0,0,0.03");
  EXPECT_THAT(OpenStatus().message(), HasSubstr("sigma_roll_deg,sigma_pitch_deg,sigma_yaw_deg"));
  // Without the sigma columns the attitude is of unknown accuracy (the filter's init sigmas).
  ReplaceLine("initial_state.csv", 1,
              "stamp_ns,roll_deg,pitch_deg,yaw_deg,v_east_mps,v_north_mps,v_up_mps");
  ReplaceLine("initial_state.csv", 2, "1317042651106324297,0,0,0,0,0,0");
  auto reader = FolderDriveReader::Open(dir_, FolderDriveReader::Options());
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_TRUE((*reader)->streams().initial_state.has_value());
  EXPECT_FALSE((*reader)->streams().initial_attitude_sigma_rpy_rad.has_value());
}

// ---- NMEA ----------------------------------------------------------------------------------
class FolderNmeaMalformedTest : public FolderMalformedTest {
 protected:
  void SetUp() override {
    FolderMalformedTest::SetUp();
    const fs::path drive = tmp_ / "2011_01_01" / "2011_01_01_drive_0001_sync";
    auto kitti = KittiDriveReader::Open(drive, KittiRawReader::Options());
    ASSERT_TRUE(kitti.ok());
    FolderWriteOptions o;
    o.gnss_format = FolderWriteOptions::GnssFormat::kNmea;
    o.overwrite = true;
    ASSERT_TRUE(WriteDriveFolder(**kitti, dir_, o).ok());
    ASSERT_TRUE(fs::exists(dir_ / "gnss.nmea"));
  }
};

TEST_F(FolderNmeaMalformedTest, WrongChecksumIsSkippedCountedAndLogged) {
  // Line 2 is the first GGA (ZDA, GGA, GST per epoch): corrupt one digit of its latitude.
  std::string gga = Line("gnss.nmea", 2);
  ASSERT_EQ(gga.substr(0, 6), "$GNGGA");
  const size_t p = gga.find(",N,") - 1;
  gga[p] = gga[p] == '1' ? '2' : '1';
  ReplaceLine("gnss.nmea", 2, gga);
  testing::LogCapture log;
  auto reader = FolderDriveReader::Open(dir_, {});
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->num_bad_nmea_sentences(), 1u);
  EXPECT_EQ((*reader)->streams().gnss.size(), 2u);  // of 3
  EXPECT_THAT(log.messages(), AllOf(HasSubstr(Path("gnss.nmea") + ":2: checksum"),
                                    HasSubstr("wrong"), HasSubstr("(sentence skipped)")));
  EXPECT_EQ((*reader)->streams().gnss_source.front(), Path("gnss.nmea") + ":5");
}

TEST_F(FolderNmeaMalformedTest, GgaWithoutDate) {
  // Without the ZDA sentences the GGAs have no date: an error naming the first GGA's line.
  std::string text = testing::ReadFile(dir_ / "gnss.nmea"), kept;
  for (size_t a = 0, b; a < text.size(); a = b + 1) {
    b = text.find('\n', a);
    const std::string line = text.substr(a, b - a + 1);
    if (line.find("ZDA") == std::string::npos) kept += line;
  }
  testing::WriteFile(dir_ / "gnss.nmea", kept);
  const Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(Path("gnss.nmea") + ":1: GGA at "),
                                 HasSubstr("before any date"), HasSubstr("nmea_utc_date")));
  FolderDriveReader::Options o;
  o.nmea_utc_date = "2011-09-26";
  auto reader = FolderDriveReader::Open(dir_, o);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->streams().gnss.size(), 3u);
  // Both GNSS files: gnss.csv wins, with a warning.
  testing::WriteFile(dir_ / "gnss.csv",
                     "stamp_ns,lat_deg,lon_deg,height_m,sigma_e_m,sigma_n_m,sigma_u_m,fix\n");
  testing::LogCapture log;
  reader = FolderDriveReader::Open(dir_, {});
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_TRUE((*reader)->streams().gnss.empty());
  EXPECT_THAT(log.messages(), HasSubstr("both gnss.csv and gnss.nmea present; gnss.csv is used"));
}

// ---- extrinsics.yaml ------------------------------------------------------------------------
TEST_F(FolderMalformedTest, ExtrinsicsNotARotationOr15Numbers) {
  const std::string f = Path("extrinsics.yaml");
  testing::WriteFile(dir_ / "extrinsics.yaml",
                     "# comment\nT_body_lidar: [1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1.01, 0, 0, 0, 0, "
                     "1]\n");
  Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(f + ":2: T_body_lidar: the rotation part is not a "
                                               "rotation (max |R^T R - I| = 0.0201")));
  testing::WriteFile(dir_ / "extrinsics.yaml",
                     "T_body_lidar: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0]\n");
  EXPECT_THAT(OpenStatus().message(),
              HasSubstr(f + ":1: T_body_lidar has 15 numbers, expected 16"));
  testing::WriteFile(dir_ / "extrinsics.yaml",
                     "T_body_lidar: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1]\n");
  EXPECT_THAT(OpenStatus().message(), HasSubstr("last row is 0.000000 0.000000 1.000000 1.000000"));
  testing::WriteFile(dir_ / "extrinsics.yaml",
                     "T_body_lidar: [-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n");
  EXPECT_THAT(OpenStatus().message(), HasSubstr("det = -1"));
  testing::WriteFile(dir_ / "extrinsics.yaml",
                     "T_body_lidar:\n  xyz: [0, 0]\n  rpy_deg: [0, 0, 0]\n");
  EXPECT_THAT(OpenStatus().message(), HasSubstr(f + ":2: T_body_lidar.xyz has 2 numbers"));
  testing::WriteFile(dir_ / "extrinsics.yaml",
                     "T_body_lidar: {xyz: [0, 0, a], rpy_deg: [0, 0, 0]}\n");
  EXPECT_THAT(OpenStatus().message(), HasSubstr("T_body_lidar.xyz[2] 'a' is not a finite number"));
  testing::WriteFile(dir_ / "extrinsics.yaml", "T_body_lidar: [1, 0\nt_body_antenna_m: [\n");
  EXPECT_THAT(OpenStatus().message(), AllOf(HasSubstr(f + ":"), HasSubstr("YAML error")));
  testing::WriteFile(dir_ / "extrinsics.yaml", "t_body_antenna_m: [0, 0, 1]\n");
  EXPECT_THAT(OpenStatus().message(), HasSubstr(f + ": key T_body_lidar missing"));
  fs::remove(dir_ / "extrinsics.yaml");
  EXPECT_EQ(OpenStatus().code(), StatusCode::kNotFound);
  FolderDriveReader::Options o;
  o.allow_missing_extrinsics = true;
  testing::LogCapture log;
  auto reader = FolderDriveReader::Open(dir_, o);
  ASSERT_TRUE(reader.ok());
  EXPECT_TRUE((*reader)->streams().T_body_lidar.matrix().isIdentity(0.0));
  EXPECT_THAT(log.messages(), HasSubstr("using identity T_body_lidar"));
}

}  // namespace
}  // namespace slam_mms
