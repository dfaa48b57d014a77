// Reader bindings: DriveReader (the adaptor interface) as a Python sequence/iterable of Scans,
// DriveStreams as numpy arrays, and the adaptors that are built: KITTI raw always, the plain
// drive folder and the ROS 1 bag readers where their headers/modules exist at configure time.

#include <limits>
#include <optional>

#include "common.hpp"
#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#ifdef SLAM_MMS_PY_WITH_FOLDER_READER
#include "slam_mms/io/drive_folder_writer.hpp"
#include "slam_mms/io/extrinsics_yaml.hpp"
#include "slam_mms/io/folder_drive_reader.hpp"
#endif
#ifdef SLAM_MMS_PY_WITH_ROSBAG
#include "slam_mms/rosbag/rosbag_drive_reader.hpp"
#include "slam_mms/rosbag/rosbag_writer.hpp"
#endif
#ifdef SLAM_MMS_PY_WITH_OPEN_DRIVE
#include "slam_mms/drive/open_drive.hpp"
#endif

namespace slam_mms::python {
namespace {

size_t CheckIndex(const DriveReader& r, py::ssize_t i) {
  const auto n = static_cast<py::ssize_t>(r.NumScans());
  if (i < 0) i += n;
  if (i < 0 || i >= n) {
    throw py::index_error("scan index out of range (" + std::to_string(n) + " scans)");
  }
  return static_cast<size_t>(i);
}

Scan ReadScanOrThrow(const DriveReader& r, size_t i) {
  return ValueOrThrow(WithoutGil([&] { return r.ReadScan(i); }));
}

// Iterates the scans of a reader in order, reading each when it is reached.
struct ScanIterator {
  py::object reader_object;  // keeps the reader alive
  const DriveReader* reader = nullptr;
  size_t next = 0;
};

py::array_t<int64_t> Stamps(size_t n, const std::function<int64_t(size_t)>& f) {
  py::array_t<int64_t> a(static_cast<py::ssize_t>(n));
  int64_t* p = a.mutable_data();
  for (size_t i = 0; i < n; ++i) p[i] = f(i);
  return a;
}

}  // namespace

void RegisterReaders(py::module_& m) {
  using DS = DriveStreams;
  py::class_<DS>(m, "DriveStreams",
                 "The non-scan streams of a drive and its calibration, as numpy arrays.")
      .def_property_readonly(
          "imu",
          [](const DS& s) {
            py::array_t<double> a({static_cast<py::ssize_t>(s.imu.size()), py::ssize_t{7}});
            auto r = a.mutable_unchecked<2>();
            for (size_t i = 0; i < s.imu.size(); ++i) {
              const auto k = static_cast<py::ssize_t>(i);
              r(k, 0) = s.imu[i].stamp.seconds();
              for (int j = 0; j < 3; ++j) r(k, 1 + j) = s.imu[i].accel_mps2(j);
              for (int j = 0; j < 3; ++j) r(k, 4 + j) = s.imu[i].gyro_radps(j);
            }
            return a;
          },
          "N x 7 [t_s ax ay az gx gy gz] (t_s rounded; exact stamps in imu_stamps_ns).")
      .def_property_readonly(
          "imu_stamps_ns",
          [](const DS& s) {
            return Stamps(s.imu.size(), [&](size_t i) { return s.imu[i].stamp.nanoseconds(); });
          })
      .def_readonly("imu_source", &DS::imu_source)
      .def_property_readonly(
          "gnss",
          [](const DS& s) {
            py::array_t<double> a({static_cast<py::ssize_t>(s.gnss.size()), py::ssize_t{6}});
            auto r = a.mutable_unchecked<2>();
            for (size_t i = 0; i < s.gnss.size(); ++i) {
              const auto k = static_cast<py::ssize_t>(i);
              const GnssFix& f = s.gnss[i];
              r(k, 0) = f.stamp.seconds();
              r(k, 1) = f.latitude_deg;
              r(k, 2) = f.longitude_deg;
              r(k, 3) = f.height_m;
              r(k, 4) = f.sigma_horizontal_m;
              r(k, 5) = f.sigma_vertical_m;
            }
            return a;
          },
          "N x 6 [t_s lat_deg lon_deg height_m sigma_h_m sigma_v_m].")
      .def_property_readonly(
          "gnss_stamps_ns",
          [](const DS& s) {
            return Stamps(s.gnss.size(), [&](size_t i) { return s.gnss[i].stamp.nanoseconds(); });
          })
      .def_property_readonly(
          "gnss_fix_type",
          [](const DS& s) {
            return Stamps(s.gnss.size(),
                          [&](size_t i) { return static_cast<int64_t>(s.gnss[i].type); });
          },
          "GnssFixType values as int (N,).")
      .def_property_readonly("gnss_num_satellites",
                             [](const DS& s) {
                               return Stamps(s.gnss.size(), [&](size_t i) {
                                 return static_cast<int64_t>(s.gnss[i].num_satellites);
                               });
                             })
      .def_readonly("gnss_source", &DS::gnss_source)
      .def_readonly("imu_samples", &DS::imu, "The IMU samples as ImuSample objects (a copy).")
      .def_readonly("gnss_fixes", &DS::gnss, "The fixes as GnssFix objects (a copy).")
      .def_property_readonly(
          "pos_stamps_ns",
          [](const DS& s) {
            return Stamps(s.pos.size(), [&](size_t i) { return s.pos[i].stamp.nanoseconds(); });
          })
      .def_property_readonly(
          "pos_llh",
          [](const DS& s) {
            py::array_t<double> a({static_cast<py::ssize_t>(s.pos.size()), py::ssize_t{3}});
            auto r = a.mutable_unchecked<2>();
            for (size_t i = 0; i < s.pos.size(); ++i) {
              const auto k = static_cast<py::ssize_t>(i);
              r(k, 0) = s.pos[i].latitude_deg;
              r(k, 1) = s.pos[i].longitude_deg;
              r(k, 2) = s.pos[i].height_m;
            }
            return a;
          },
          "External POS positions N x 3 [lat_deg lon_deg height_m] (empty: none).")
      .def_property_readonly("pos_R_enu_body",
                             [](const DS& s) {
                               py::array_t<double> a({static_cast<py::ssize_t>(s.pos.size()),
                                                      py::ssize_t{3}, py::ssize_t{3}});
                               auto r = a.mutable_unchecked<3>();
                               for (size_t i = 0; i < s.pos.size(); ++i) {
                                 for (int j = 0; j < 3; ++j) {
                                   for (int k = 0; k < 3; ++k) {
                                     r(static_cast<py::ssize_t>(i), j, k) =
                                         s.pos[i].R_enu_body(j, k);
                                   }
                                 }
                               }
                               return a;
                             })
      .def_readonly("pos_source", &DS::pos_source)
      .def_readonly("initial_state", &DS::initial_state, "InsState or None.")
      .def_readonly("initial_state_source", &DS::initial_state_source)
      .def_readonly("initial_attitude_sigma_rpy_rad", &DS::initial_attitude_sigma_rpy_rad,
                    "(3,) 1-sigma roll, pitch, yaw [rad] of initial_state's attitude as its "
                    "source states it, or None (the filter's init sigmas).")
      .def_readonly("imu_noise", &DS::imu_noise,
                    "ImuNoiseSpec as the input states it (imu_noise.yaml), or None.")
      .def_readonly("imu_noise_source", &DS::imu_noise_source)
      .def_readonly("imu_frame_is_vehicle_frame", &DS::imu_frame_is_vehicle_frame,
                    "True where the input states that its IMU frame is the vehicle's (KITTI raw).")
      .def_property_readonly("T_body_lidar",
                             [](const DS& s) { return IsometryToArray(s.T_body_lidar); })
      .def_readonly("t_body_antenna_m", &DS::t_body_antenna_m, "(3,) or None.");

  py::class_<ScanIterator>(m, "_ScanIterator")
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", [](ScanIterator& it) {
        if (it.next >= it.reader->NumScans()) throw py::stop_iteration();
        return ReadScanOrThrow(*it.reader, it.next++);
      });

  py::class_<DriveReader>(m, "DriveReader",
                          "A drive input (the C++ DriveReader adaptor): a sequence of Scans read "
                          "one at a time, plus the IMU/GNSS/POS streams.")
      .def("describe", &DriveReader::Describe)
      .def("__len__", &DriveReader::NumScans)
      .def(
          "__getitem__",
          [](const DriveReader& r, py::ssize_t i) { return ReadScanOrThrow(r, CheckIndex(r, i)); },
          py::arg("i"), "Reads scan i (IndexError out of range; DataLoss -> slam_mms.Error).")
      .def(
          "__iter__",
          [](py::object self) {
            return ScanIterator{self, &self.cast<const DriveReader&>(), 0};
          },
          "Iterates the scans in time order (each read when reached).")
      .def(
          "read_scan",
          [](const DriveReader& r, py::ssize_t i) { return ReadScanOrThrow(r, CheckIndex(r, i)); },
          py::arg("i"))
      .def(
          "scan_start_ns",
          [](const DriveReader& r, py::ssize_t i) {
            return r.ScanStart(CheckIndex(r, i)).nanoseconds();
          },
          py::arg("i"))
      .def(
          "scan_end_ns",
          [](const DriveReader& r, py::ssize_t i) {
            return r.ScanEnd(CheckIndex(r, i)).nanoseconds();
          },
          py::arg("i"))
      .def(
          "scan_source",
          [](const DriveReader& r, py::ssize_t i) { return r.ScanSource(CheckIndex(r, i)); },
          py::arg("i"))
      .def_property_readonly(
          "scan_starts_ns",
          [](const DriveReader& r) {
            return Stamps(r.NumScans(), [&](size_t i) { return r.ScanStart(i).nanoseconds(); });
          })
      .def_property_readonly("scan_ends_ns",
                             [](const DriveReader& r) {
                               return Stamps(r.NumScans(),
                                             [&](size_t i) { return r.ScanEnd(i).nanoseconds(); });
                             })
      .def_property_readonly("streams", &DriveReader::streams,
                             py::return_value_policy::reference_internal)
      .def_property_readonly(
          "T_body_lidar",
          [](const DriveReader& r) { return IsometryToArray(r.streams().T_body_lidar); })
      .def_property_readonly("total_dropped_points", &DriveReader::TotalDroppedPoints)
      .def("__repr__", [](const DriveReader& r) {
        return "<" + r.Describe() + ": " + std::to_string(r.NumScans()) + " scans>";
      });

  py::enum_<SpinDirection>(m, "SpinDirection")
      .value("CLOCKWISE", SpinDirection::kClockwise)
      .value("COUNTER_CLOCKWISE", SpinDirection::kCounterClockwise);
  py::enum_<KittiRawLayout>(m, "KittiRawLayout")
      .value("SYNC", KittiRawLayout::kSync)
      .value("EXTRACT", KittiRawLayout::kExtract);

  using KO = KittiRawReader::Options;
  py::class_<KO>(m, "KittiRawReaderOptions", "KittiRawReader::Options (frame range inclusive).")
      .def(py::init<>())
      .def_readwrite("first_frame", &KO::first_frame)
      .def_readwrite("last_frame", &KO::last_frame, "-1 = the drive's last frame")
      .def_readwrite("spin", &KO::spin)
      .def_readwrite("vertical_angle_correction", &KO::vertical_angle_correction)
      .def_readwrite("vertical_correction_deg", &KO::vertical_correction_deg)
      .def_readwrite("per_point_time", &KO::per_point_time)
      .def_readwrite("calib_dir", &KO::calib_dir)
      .def_readwrite("allow_missing_calibration", &KO::allow_missing_calibration)
      .def_readwrite("imu_time_margin_s", &KO::imu_time_margin_s)
      .def("validate", [](const KO& o) { ThrowIfError(o.Validate()); })
      .attr("_fields") = py::make_tuple(
      "first_frame", "last_frame", "spin", "vertical_angle_correction", "vertical_correction_deg",
      "per_point_time", "calib_dir", "allow_missing_calibration", "imu_time_margin_s");

  py::class_<KittiDriveReader, DriveReader>(
      m, "KittiRawReader",
      "A KITTI raw drive folder (…/2011_09_26_drive_0013_sync) as a DriveReader: scans with "
      "azimuth per-point times, OXTS records as IMU samples and GNSS fixes, T_body_lidar from "
      "calib_imu_to_velo.txt.")
      .def(py::init([](const std::filesystem::path& drive_dir, std::optional<KO> options,
                       int64_t first_frame, int64_t last_frame) {
             KO o = options.value_or(KO());
             if (!options) {
               o.first_frame = first_frame;
               o.last_frame = last_frame;
             }
             return ValueOrThrow(WithoutGil([&] { return KittiDriveReader::Open(drive_dir, o); }));
           }),
           py::arg("drive_dir"), py::arg("options") = py::none(), py::arg("first_frame") = 0,
           py::arg("last_frame") = -1,
           "Opens the drive (FileNotFoundError / ValueError / slam_mms.Error naming the file). "
           "first_frame/last_frame (inclusive) apply when options is None.")
      .def_property_readonly("drive_dir",
                             [](const KittiDriveReader& r) { return r.kitti().drive_dir(); })
      .def_property_readonly("layout", [](const KittiDriveReader& r) { return r.kitti().layout(); })
      .def_property_readonly("has_imu_100hz",
                             [](const KittiDriveReader& r) { return r.kitti().HasImu100Hz(); })
      .def(
          "frame_index",
          [](const KittiDriveReader& r, py::ssize_t i) {
            return r.kitti().FrameIndex(CheckIndex(r, i));
          },
          py::arg("i"), "File number of scan i.")
      .def_property_readonly("calibration_file", [](const KittiDriveReader& r) {
        return r.kitti().calibration_file();
      });
  m.attr("KittiDriveReader") = m.attr("KittiRawReader");

  m.def(
      "oxts_inertial_delay_s",
      [](const DriveReader& reader) -> std::optional<double> {
        if (const auto* k = dynamic_cast<const KittiDriveReader*>(&reader.Underlying())) {
          return k->kitti().oxts_inertial_delay_s();
        }
        return std::nullopt;
      },
      py::arg("reader"),
      "KITTI raw drives: how long before its OXTS record each IMU sample is stamped [s] "
      "(KittiRawReader::oxts_inertial_delay_s: KITTI's OXTS rates lag its attitudes; estimated "
      "from the records); None for other drives.");
#ifdef SLAM_MMS_PY_WITH_OPEN_DRIVE
  m.def(
      "_open_drive",
      [](const std::filesystem::path& path, const std::string& kind, int64_t first_frame,
         int64_t last_frame, std::string lidar_topic, std::string imu_topic, std::string gnss_topic,
         std::filesystem::path extrinsics, double kitti_vertical_correction_deg) {
        DriveSourceOptions o;
        if (kind == "auto") {
          o.kind = DriveSourceKind::kAuto;
        } else if (kind == "kitti_raw") {
          o.kind = DriveSourceKind::kKittiRaw;
        } else if (kind == "folder") {
          o.kind = DriveSourceKind::kFolder;
        } else if (kind == "rosbag") {
          o.kind = DriveSourceKind::kRosbag;
        } else {
          throw py::value_error("kind = '" + kind + "'; must be auto, kitti_raw, folder or rosbag");
        }
        o.first_frame = first_frame;
        o.last_frame = last_frame;
        o.lidar_topic = std::move(lidar_topic);
        o.imu_topic = std::move(imu_topic);
        o.gnss_topic = std::move(gnss_topic);
        o.extrinsics = std::move(extrinsics);
        o.kitti_vertical_correction_deg = kitti_vertical_correction_deg;
        return ValueOrThrow(WithoutGil([&] { return OpenDrive(path, o); }));
      },
      py::arg("path"), py::arg("kind") = "auto", py::arg("first_frame") = 0,
      py::arg("last_frame") = -1, py::arg("lidar_topic") = "", py::arg("imu_topic") = "",
      py::arg("gnss_topic") = "", py::arg("extrinsics") = "",
      py::arg("kitti_vertical_correction_deg") = 0.0,
      "The C++ OpenDrive: a KITTI raw folder, a plain drive folder or a ROS 1 bag as a "
      "DriveReader (kind 'auto' detects it).");
  m.attr("HAVE_OPEN_DRIVE") = true;
#else
  m.attr("HAVE_OPEN_DRIVE") = false;
#endif
#ifdef SLAM_MMS_PY_WITH_FOLDER_READER
  py::class_<FolderDriveReader, DriveReader>(
      m, "FolderDriveReader",
      "A plain drive folder (scans.csv + point files, imu.csv, gnss.csv or NMEA, extrinsics.yaml; "
      "docs/drive_folder.md) as a DriveReader.")
      .def(py::init([](const std::filesystem::path& dir, int64_t first_frame, int64_t last_frame,
                       bool per_point_time, bool allow_missing_extrinsics,
                       std::string nmea_utc_date) {
             FolderDriveReader::Options o;
             o.first_frame = first_frame;
             o.last_frame = last_frame;
             o.per_point_time = per_point_time;
             o.allow_missing_extrinsics = allow_missing_extrinsics;
             o.nmea_utc_date = std::move(nmea_utc_date);
             ThrowIfError(o.Validate());
             return ValueOrThrow(WithoutGil([&] { return FolderDriveReader::Open(dir, o); }));
           }),
           py::arg("dir"), py::arg("first_frame") = 0, py::arg("last_frame") = -1,
           py::arg("per_point_time") = true, py::arg("allow_missing_extrinsics") = false,
           py::arg("nmea_utc_date") = "")
      .def_property_readonly("dir", &FolderDriveReader::dir)
      .def_property_readonly("num_bad_nmea_sentences", &FolderDriveReader::num_bad_nmea_sentences);
  m.def(
      "write_drive_folder",
      [](const DriveReader& reader, const std::filesystem::path& dir,
         const std::string& scan_format, const std::string& gnss_format, bool write_point_time,
         int nmea_time_decimals, bool overwrite) {
        using SF = FolderWriteOptions::ScanFormat;
        using GF = FolderWriteOptions::GnssFormat;
        FolderWriteOptions o;
        if (scan_format == "pcd_binary") {
          o.scan_format = SF::kPcdBinary;
        } else if (scan_format == "pcd_ascii") {
          o.scan_format = SF::kPcdAscii;
        } else if (scan_format == "ply_binary") {
          o.scan_format = SF::kPlyBinary;
        } else if (scan_format == "ply_ascii") {
          o.scan_format = SF::kPlyAscii;
        } else if (scan_format == "bin") {
          o.scan_format = SF::kBin;
        } else {
          throw py::value_error("scan_format = '" + scan_format +
                                "'; must be pcd_binary, pcd_ascii, ply_binary, ply_ascii or bin");
        }
        if (gnss_format == "csv") {
          o.gnss_format = GF::kCsv;
        } else if (gnss_format == "nmea") {
          o.gnss_format = GF::kNmea;
        } else {
          throw py::value_error("gnss_format = '" + gnss_format + "'; must be csv or nmea");
        }
        o.write_point_time = write_point_time;
        o.nmea_time_decimals = nmea_time_decimals;
        o.overwrite = overwrite;
        ThrowIfError(o.Validate());
        ThrowIfError(WithoutGil([&] { return WriteDriveFolder(reader, dir, o); }));
      },
      py::arg("reader"), py::arg("dir"), py::arg("scan_format") = "pcd_binary",
      py::arg("gnss_format") = "csv", py::arg("write_point_time") = false,
      py::arg("nmea_time_decimals") = 3, py::arg("overwrite") = false,
      "The C++ WriteDriveFolder: any DriveReader's drive as a plain drive folder "
      "(docs/drive_folder.md) that FolderDriveReader reads back.");
  m.def(
      "write_extrinsics_yaml",
      [](const std::filesystem::path& path, py::object T_body_lidar, py::object t_body_antenna_m,
         std::optional<bool> imu_frame_is_vehicle_frame) {
        DriveExtrinsics e;
        e.imu_frame_is_vehicle_frame = imu_frame_is_vehicle_frame;
        e.T_body_lidar = ArrayToIsometry(T_body_lidar, "T_body_lidar");
        if (!t_body_antenna_m.is_none()) {
          auto a = py::array_t<double, py::array::forcecast>::ensure(t_body_antenna_m);
          if (!a || a.ndim() != 1 || a.shape(0) != 3) {
            throw py::value_error("t_body_antenna_m: expected shape (3,)");
          }
          e.t_body_antenna_m = Eigen::Vector3d(a.at(0), a.at(1), a.at(2));
        }
        ThrowIfError(WriteExtrinsicsYaml(e, path));
      },
      py::arg("path"), py::arg("T_body_lidar"), py::arg("t_body_antenna_m") = py::none(),
      py::arg("imu_frame_is_vehicle_frame") = py::none(),
      "extrinsics.yaml (the drive folder's, also --extrinsics of a bag) with T_body_lidar 4 x 4; "
      "imu_frame_is_vehicle_frame: the statement that the IMU frame is the car's (None: not "
      "stated).");
  m.attr("HAVE_FOLDER_READER") = true;
#else
  m.attr("HAVE_FOLDER_READER") = false;
#endif
#ifdef SLAM_MMS_PY_WITH_ROSBAG
  py::class_<RosbagDriveReader, DriveReader>(
      m, "RosbagDriveReader",
      "A ROS 1 bag (sensor_msgs/PointCloud2, Imu, NavSatFix) as a DriveReader.")
      .def(py::init([](const std::filesystem::path& bag, std::string lidar_topic,
                       std::string imu_topic, std::string gnss_topic, int64_t first_scan,
                       int64_t last_scan, py::object T_body_lidar) {
             RosbagDriveReader::Options o;
             o.lidar_topic = std::move(lidar_topic);
             o.imu_topic = std::move(imu_topic);
             o.gnss_topic = std::move(gnss_topic);
             o.first_scan = first_scan;
             o.last_scan = last_scan;
             if (!T_body_lidar.is_none())
               o.T_body_lidar = ArrayToIsometry(T_body_lidar, "T_body_lidar");
             ThrowIfError(o.Validate());
             return ValueOrThrow(WithoutGil([&] { return RosbagDriveReader::Open(bag, o); }));
           }),
           py::arg("bag"), py::arg("lidar_topic") = "", py::arg("imu_topic") = "",
           py::arg("gnss_topic") = "", py::arg("first_scan") = 0, py::arg("last_scan") = -1,
           py::arg("T_body_lidar") = py::none(),
           "Opens a bag; topics '' = the only one of each type (see docs/rosbag.md).")
      .def_static(
          "list_topics",
          [](const std::filesystem::path& bag) {
            const std::vector<RosbagTopic> topics =
                ValueOrThrow(WithoutGil([&] { return RosbagDriveReader::ListTopics(bag); }));
            py::list out;
            for (const RosbagTopic& t : topics) {
              out.append(py::make_tuple(t.name, t.datatype, t.num_messages));
            }
            return out;
          },
          py::arg("bag"), "[(name, datatype, num_messages), ...]");
  m.def(
      "write_rosbag",
      [](const DriveReader& reader, const std::filesystem::path& bag, bool write_point_time,
         const std::string& lidar_topic, const std::string& imu_topic,
         const std::string& gnss_topic) {
        RosbagWriteOptions o;
        o.write_point_time = write_point_time;
        o.lidar_topic = lidar_topic;
        o.imu_topic = imu_topic;
        o.gnss_topic = gnss_topic;
        ThrowIfError(o.Validate());
        ThrowIfError(WithoutGil([&] { return WriteRosbag(reader, bag, o); }));
      },
      py::arg("reader"), py::arg("bag"), py::arg("write_point_time") = true,
      py::arg("lidar_topic") = "/velodyne_points", py::arg("imu_topic") = "/imu/data",
      py::arg("gnss_topic") = "/gps/fix",
      "The C++ WriteRosbag: any DriveReader's drive as a ROS 1 bag (no extrinsics inside: "
      "write_extrinsics_yaml and open it with extrinsics=...).");
  m.attr("HAVE_ROSBAG_READER") = true;
#else
  m.attr("HAVE_ROSBAG_READER") = false;
#endif
}

}  // namespace slam_mms::python
