""".param files in MAVProxy's and Mission Planner's formats, and comparing one with the vehicle."""
from __future__ import annotations

from pymavlink.mavparm import MAVParmDict

from driver.params.files import (Difference, ParamFormat, compare, param_file_text, read_param_file,
                                 write_param_file)
from driver.params.model import Parameter, ParameterTable, ParamType

TABLE = ParameterTable({p.name: p for p in (
    Parameter("WPNAV_SPEED", 1000.0, ParamType.REAL32, 0), Parameter("FS_GCS_ENABLE", 0, ParamType.INT8, 1),
    Parameter("RTL_ALT", 1e9, ParamType.INT32, 2), Parameter("ATC_ANG_RLL_P", 4.5, ParamType.REAL32, 3),
    Parameter("INS_GYRO_FILTER", 20, ParamType.INT16, 4), Parameter("FORMAT_VERSION", 120, ParamType.INT16, 5),
    Parameter("PSC_ACC_XY_FILT", 0.30000001192092896, ParamType.REAL32, 6))}, expected=7)


def test_both_formats_round_trip_and_mavproxy_reads_ours(tmp_path):
    for fmt, first in ((ParamFormat.MAVPROXY, "ATC_ANG_RLL_P    4.5"), (ParamFormat.MISSION_PLANNER, "ATC_ANG_RLL_P,4.5")):
        path = str(tmp_path / f"{fmt.value}.param")
        assert write_param_file(path, TABLE, fmt) == 7
        text = open(path).read()
        assert text.splitlines()[0] == first
        assert "RTL_ALT" in text and "1000000000" in text and "0.3\n" in text
        back = read_param_file(path)
        assert not back.problems and back.excluded == ["FORMAT_VERSION"]
        assert compare(back.values, TABLE) == []
    theirs = MAVParmDict()                                   # pymavlink's own reader, as MAVProxy loads a file
    assert theirs.load(str(tmp_path / "mavproxy.param"), use_excludes=False)
    assert theirs["FS_GCS_ENABLE"] == 0 and theirs["PSC_ACC_XY_FILT"] == 0.3 and theirs["RTL_ALT"] == 1e9


def test_reading_comments_hex_and_mistakes(tmp_path):
    path = tmp_path / "mixed.param"
    path.write_text("# saved by hand\nWPNAV_SPEED, 750  # faster\nfs_gcs_enable 0x1\n\nBROKEN\nRTL_ALT lots\n"
                    "SYS_NUM_RESETS 12\n")
    f = read_param_file(str(path))
    assert f.values == {"WPNAV_SPEED": 750.0, "FS_GCS_ENABLE": 1.0}
    assert [p.split(":")[0] for p in f.problems] == ["line 5", "line 6"] and f.excluded == ["SYS_NUM_RESETS"]


def test_compare_at_each_types_precision():
    values = {"WPNAV_SPEED": 1000.00001, "FS_GCS_ENABLE": 1, "RTL_ALT": 1e9, "NOT_THERE": 3, "INS_GYRO_FILTER": 20.0}
    assert compare(values, TABLE) == [Difference("FS_GCS_ENABLE", 1, 0, ParamType.INT8),
                                      Difference("NOT_THERE", 3, None)]
    assert compare(values, TABLE, pattern="fs_*") == [Difference("FS_GCS_ENABLE", 1, 0, ParamType.INT8)]
    everything = compare(values, TABLE, include_vehicle_only=True)
    assert {d.name: d.kind for d in everything} == {"FS_GCS_ENABLE": "changed", "NOT_THERE": "not on the vehicle",
                                                   "ATC_ANG_RLL_P": "not in the file",
                                                   "PSC_ACC_XY_FILT": "not in the file"}


def test_a_pattern_saves_part_of_the_table():
    assert param_file_text(TABLE, ParamFormat.MISSION_PLANNER, "rtl*") == "RTL_ALT,1000000000\n"
