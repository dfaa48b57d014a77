"""slam_mms_run's YAML --config reader through the package (apply_config_file / apply_config_text,
options_to_yaml / options_to_json): the same code as the app (config_file.cpp compiled in)."""
import json
import os
import subprocess
import sys

import pytest

import slam_mms
from slam_mms import _slam_mms as _C


def test_config_yaml_nested_and_dotted(tmp_path):
    cfg = tmp_path / "my.yaml"
    cfg.write_text("localizer:\n  submap_duration_s: 4.5\nlevel2.use_loops: off\n")
    o = slam_mms.Options()
    slam_mms.apply_config_file(cfg, o)
    j = json.loads(slam_mms.options_to_json(o))
    assert j["localizer"]["submap_duration_s"] == 4.5
    assert j["level2"]["use_loops"] is False
    # Untouched keys keep the defaults.
    d = json.loads(slam_mms.options_to_json(slam_mms.Options()))
    assert j["level2"]["loop_distance_m"] == d["level2"]["loop_distance_m"]


def test_config_yaml_errors_name_file_line_key(tmp_path):
    cfg = tmp_path / "bad.yaml"
    cfg.write_text("localizer:\n  submap_duration_s: 5\n  bogus_key: 3\n")
    with pytest.raises(ValueError, match=r"bad.yaml:3: unknown key 'localizer.bogus_key'"):
        slam_mms.apply_config_file(cfg, slam_mms.Options())
    with pytest.raises(ValueError, match=r"x:1: key 'level2.use_loops': bad value 'maybe'"):
        slam_mms.apply_config_text("level2.use_loops: maybe\n", slam_mms.Options(), "x")
    with pytest.raises(ValueError, match=r"x:2: key 'num_threads': expected int, got a list"):
        slam_mms.apply_config_text("# c\nnum_threads: [1]\n", slam_mms.Options(), "x")


def test_config_dump_read_dump_identical():
    o = slam_mms.Options()
    slam_mms.apply_config_text("localizer: {submap_duration_s: 0.30000000000000004}\n"
                               "ins.gnss.t_body_antenna: [0.1, 0.2, 0.75]\n", o)
    text = slam_mms.options_to_yaml(o)
    back = slam_mms.Options()
    slam_mms.apply_config_text(text, back)
    assert slam_mms.options_to_yaml(back) == text
    assert slam_mms.options_to_json(back) == slam_mms.options_to_json(o)
    assert "submap_duration_s: 0.30000000000000004  # double; default" in text


def test_python_cli_config_keys_is_yaml(tmp_path):
    # python -m slam_mms run --config-keys prints a YAML file that --config reads back.
    env = dict(os.environ)
    r = subprocess.run([sys.executable, "-m", "slam_mms", "run", "--config-keys"],
                       capture_output=True, text=True, env=env, timeout=60)
    assert r.returncode == 0, r.stderr
    # The app's defaults: the library's, with finished submaps spilled into --out ("<out>").
    defaults = _C.Options()
    defaults.localizer.spill_dir = "<out>"
    assert r.stdout == slam_mms.options_to_yaml(defaults)
    o = slam_mms.Options()
    slam_mms.apply_config_text(r.stdout, o, "keys.yaml")
    assert slam_mms.options_to_yaml(o) == r.stdout


def test_report_embeds_options_and_issue22_fields():
    o = slam_mms.Options()
    slam_mms.apply_config_text("level2.use_loops: false\n", o)
    text = slam_mms.report_to_json(
        "d", 9, 1.0, "none", [], [], None, kind="folder", scans_total=10,
        skipped_scans=[("scans/0004.pcd", "truncated")], command_line=["slam_mms_run", "--out=x"],
        options_json=slam_mms.options_to_json(o), complete=False, outputs=["full.tum"])
    r = json.loads(text)
    assert r["version"] and r["complete"] is False
    assert r["command_line"] == ["slam_mms_run", "--out=x"]
    assert r["input"]["kind"] == "folder" and r["input"]["scans_total"] == 10
    assert r["input"]["scans"] == r["input"]["scans_processed"] == 9
    assert r["input"]["skipped_scans"] == {
        "count": 1, "scans": [{"source": "scans/0004.pcd", "reason": "truncated"}]}
    assert r["options"]["level2"]["use_loops"] is False
    assert r["options"] == json.loads(slam_mms.options_to_json(o))
    assert r["georef"] is None and r["outputs"] == {"files": ["full.tum"]}
    assert r["extrinsics"] is None
    with pytest.raises(ValueError, match="options_json"):
        slam_mms.report_to_json("d", 1, 1.0, "none", [], [], options_json="{bad")
