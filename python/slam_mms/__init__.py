"""slam_mms: the SLAM-integrated mobile mapping system (Li et al., ISPRS J. 2020) from Python.

The package wraps the C++ SDK (pybind11 extension ``slam_mms._slam_mms``) and never reimplements
it: :class:`MappingSystem` is the C++ ``MappingSystem``, :func:`run_drive` calls the C++
``RunDrive`` (so its trajectory equals ``slam_mms_run``'s bit for bit), readers are the C++
``DriveReader`` adaptors, the metrics and report.json come from the C++ eval module.

Quick start::

    import slam_mms
    drive = slam_mms.simulate_drive("/tmp/sim", duration_s=10)
    result = slam_mms.run_drive(drive, mode="full")
    result.trajectory      # N x 8 TUM rows [t_s x y z qx qy qz qw] (float64)
    result.map_points      # M x 4 [x y z intensity] (float32), world = local ENU
    result.report          # dict, as report.json

Conventions: stamps are integer nanoseconds since the epoch (``*_ns``); poses are
``T_world_body`` with world the local ENU frame at :attr:`MappingSystem.origin`; covariances are
6 x 6, rotation first. Library log messages go to the Python logger ``"slam_mms"``.
The GIL is released while the library processes (``add_*``, ``finish``, ``run_drive``, readers,
metrics, the simulator).
"""

from __future__ import annotations

import sys as _sys

try:
    from . import _slam_mms as _C
except ImportError:  # a build tree: the extension lies beside the package on sys.path
    import _slam_mms as _C  # type: ignore[no-redef]

    _sys.modules[__name__ + "._slam_mms"] = _C

__version__: str = _C.__version__

# ---- the SDK, as bound ----------------------------------------------------------------------
Error = _C.Error
LogLevel = _C.LogLevel
GnssFixType = _C.GnssFixType
GnssAvailability = _C.GnssAvailability
MappingMode = _C.MappingMode
SurfelRendererBackend = _C.SurfelRendererBackend
WindowExitMode = _C.WindowExitMode
InconsistencyAction = _C.InconsistencyAction
MotionFactorType = _C.MotionFactorType
IcpTermination = _C.IcpTermination
Alignment = _C.Alignment
SpinDirection = _C.SpinDirection
KittiRawLayout = _C.KittiRawLayout

GeodeticPoint = _C.GeodeticPoint
ImuSample = _C.ImuSample
GnssFix = _C.GnssFix
InsState = _C.InsState
Scan = _C.Scan
Trajectory = _C.Trajectory

Options = _C.Options
InsOptions = _C.InsOptions
GnssPriorOptions = _C.GnssPriorOptions
GnssErrorModel = _C.GnssErrorModel
LocalizerOptions = _C.LocalizerOptions
Level2Options = _C.Level2Options
SurfelMapOptions = _C.SurfelMapOptions
SurfelRendererOptions = _C.SurfelRendererOptions
RangeProjectionOptions = _C.RangeProjectionOptions
ProjectiveIcpOptions = _C.ProjectiveIcpOptions
PointIcpOptions = _C.PointIcpOptions
SlidingWindowOptions = _C.SlidingWindowOptions
DeskewOptions = _C.DeskewOptions
DynamicObjectOptions = _C.DynamicObjectOptions
ImuPreintegrationOptions = _C.ImuPreintegrationOptions
ImuNoiseSpec = _C.ImuNoiseSpec

MappingSystem = _C.MappingSystem
LocalizationResult = _C.LocalizationResult
DriveRun = _C.DriveRun

DriveReader = _C.DriveReader
DriveStreams = _C.DriveStreams
KittiRawReader = _C.KittiRawReader
KittiDriveReader = _C.KittiDriveReader
KittiRawReaderOptions = _C.KittiRawReaderOptions
HAVE_FOLDER_READER: bool = _C.HAVE_FOLDER_READER
HAVE_ROSBAG_READER: bool = _C.HAVE_ROSBAG_READER
HAVE_OPEN_DRIVE: bool = _C.HAVE_OPEN_DRIVE
if HAVE_FOLDER_READER:
    FolderDriveReader = _C.FolderDriveReader
    write_drive_folder = _C.write_drive_folder
    write_extrinsics_yaml = _C.write_extrinsics_yaml
if HAVE_ROSBAG_READER:
    RosbagDriveReader = _C.RosbagDriveReader
    write_rosbag = _C.write_rosbag

AteResult = _C.AteResult
RelativeErrorResult = _C.RelativeErrorResult
OutageErrorResult = _C.OutageErrorResult
MapEntropyResult = _C.MapEntropyResult
MethodReport = _C.MethodReport
compute_ate = _C.compute_ate
compute_relative_error = _C.compute_relative_error
compute_outage_errors = _C.compute_outage_errors
compute_map_entropy = _C.compute_map_entropy
make_method_report = _C.make_method_report
report_to_json = _C.report_to_json
peak_rss_mb = _C.peak_rss_mb
read_ply = _C.read_ply
write_map = _C.write_map
apply_config_file = _C.apply_config_file
apply_config_text = _C.apply_config_text
options_to_yaml = _C.options_to_yaml
options_to_json = _C.options_to_json
config_keys = _C.config_keys
load_ground_truth = _C.load_ground_truth
has_simulator_ground_truth = _C.has_simulator_ground_truth
plot_trajectories_top_view = _C.plot_trajectories_top_view
plot_position_errors = _C.plot_position_errors
plot_map_height = _C.plot_map_height
write_scan_results_csv = _C.write_scan_results_csv
apply_input_models = _C.apply_input_models
parse_mapping_mode = _C.parse_mapping_mode
set_min_log_level = _C.set_min_log_level
flush_log = _C.flush_log


def _options_repr(self) -> str:
    fields = ", ".join(f"{name}={getattr(self, name)!r}" for name in type(self)._fields)
    return f"{type(self).__name__}({fields})"


def _options_to_dict(self) -> dict:
    """The fields as a dict (nested options as dicts, arrays as lists)."""
    out = {}
    for name in type(self)._fields:
        value = getattr(self, name)
        if hasattr(type(value), "_fields"):
            value = value.to_dict()
        elif hasattr(value, "tolist"):
            value = value.tolist()
        elif hasattr(value, "name") and hasattr(value, "value"):  # a bound enum
            value = value.name
        out[name] = value
    return out


for _cls in (Options, InsOptions, GnssPriorOptions, GnssErrorModel, LocalizerOptions, Level2Options,
             SurfelMapOptions, SurfelRendererOptions, RangeProjectionOptions,
             ProjectiveIcpOptions, PointIcpOptions, SlidingWindowOptions, DeskewOptions,
             DynamicObjectOptions,
             ImuPreintegrationOptions, KittiRawReaderOptions):
    _cls.__repr__ = _options_repr
    _cls.to_dict = _options_to_dict
del _cls

from ._logging import install_log_handler, remove_log_handler  # noqa: E402
from ._drive import DriveResult, open_drive, run_drive, simulate_drive  # noqa: E402

install_log_handler()

__all__ = [name for name in dir() if not name.startswith("_")]
