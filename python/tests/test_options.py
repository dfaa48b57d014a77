"""Options: every field with the C++ defaults, nested objects edited in place, validation errors
as ValueError naming the field."""

from __future__ import annotations

import numpy as np
import pytest

import slam_mms


def test_defaults_are_the_cpp_defaults():
    o = slam_mms.Options()
    assert o.mode == slam_mms.MappingMode.FULL
    np.testing.assert_array_equal(o.T_body_lidar, np.eye(4))
    assert o.origin is None and o.gnss_outages == []
    assert (o.map_max_range_m, o.map_voxel_m, o.num_threads) == (60.0, 0.1, 2)
    assert (o.max_pos_jump_m, o.max_pos_jump_rad) == (0.06, 0.006)
    assert o.ins.gyro_noise_density == 1.7e-4 and o.ins.history_s == 600.0
    assert o.ins.gnss.outage_timeout_s == 1.5
    assert o.ins.gnss.min_fix_type == slam_mms.GnssFixType.SINGLE
    assert o.localizer.submap_duration_s == 5.0
    assert o.localizer.surfels.renderer.projection.cols == 1024  # Localizer's own default
    assert o.localizer.icp.max_iterations == 20
    assert o.localizer.window.exit_mode == slam_mms.WindowExitMode.MARGINALIZE
    assert o.localizer.renderer == slam_mms.SurfelRendererBackend.AUTO
    assert o.level2.loop_distance_m == 25.0 and o.level2.gnss_correlation_s == 10.0
    assert o.level2.icp.num_normal_neighbors == 10
    o.validate()


def test_every_field_is_exposed():
    # The C++ MappingSystem::Options members, in declaration order.
    assert slam_mms.Options._fields == (
        "mode", "T_body_lidar", "origin", "gnss_outages", "ins", "localizer", "level2",
        "map_max_range_m", "map_voxel_m", "max_pos_jump_m", "max_pos_jump_rad", "num_threads",
        "use_stated_imu_noise", "vehicle_nhc_sigma_mps")
    d = slam_mms.Options().to_dict()
    assert d["localizer"]["icp"]["max_iterations"] == 20
    assert d["mode"] == "FULL"


def test_nested_options_are_edited_in_place_and_copies_are_deep():
    o = slam_mms.Options()
    o.localizer.icp.max_iterations = 7
    o.ins.gnss.t_body_antenna = [0.1, 0.2, 0.3]
    assert o.localizer.icp.max_iterations == 7
    np.testing.assert_array_equal(o.ins.gnss.t_body_antenna, [0.1, 0.2, 0.3])
    c = o.copy()
    c.localizer.icp.max_iterations = 9
    assert o.localizer.icp.max_iterations == 7
    o.origin = slam_mms.GeodeticPoint(49.0, 8.4, 110.0)
    o.gnss_outages = [(10.0, 5.0)]
    assert o.origin.latitude_deg == 49.0 and o.gnss_outages == [(10.0, 5.0)]


@pytest.mark.parametrize("edit, field", [
    (lambda o: setattr(o, "num_threads", 0), r"MappingSystem::Options::num_threads = 0"),
    (lambda o: setattr(o, "map_voxel_m", -1.0), r"MappingSystem::Options::map_voxel_m"),
    (lambda o: setattr(o, "gnss_outages", [(1.0, -2.0)]), r"gnss_outages\[0\]"),
    (lambda o: setattr(o.ins.gnss, "outage_timeout_s", -1.0), r"outage_timeout_s"),
    (lambda o: setattr(o.localizer, "submap_duration_s", 0.0), r"submap_duration_s"),
    (lambda o: setattr(o.level2, "loop_distance_m", -1.0), r"loop_distance_m"),
])
def test_validation_error_is_value_error_naming_the_field(edit, field):
    o = slam_mms.Options()
    edit(o)
    with pytest.raises(ValueError, match=field):
        o.validate()
    with pytest.raises(ValueError, match=field):
        slam_mms.MappingSystem(o)


def test_bad_matrix_is_value_error():
    o = slam_mms.Options()
    with pytest.raises(ValueError, match="T_body_lidar: expected a 4 x 4"):
        o.T_body_lidar = np.eye(3)
    bad = np.eye(4)
    bad[0, 0] = 2.0
    o.T_body_lidar = bad
    with pytest.raises(ValueError, match="T_body_lidar has a rotation that is not orthonormal"):
        slam_mms.MappingSystem(o)


def test_mode_names():
    assert slam_mms.parse_mapping_mode("lidar_only") == slam_mms.MappingMode.LIDAR_ONLY
    with pytest.raises(ValueError, match="mode = 'slam'"):
        slam_mms.parse_mapping_mode("slam")
