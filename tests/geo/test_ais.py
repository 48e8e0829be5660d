"""AIS logs read into trajectories (ctxmodels.geo.ais): a small hand-made log with each
rule in it, the errors, and the Solent log Stone Soup publishes (downloaded at first use)."""
import datetime as dt

import numpy as np
import pytest

from ctxmodels.geo.ais import KNOT, read_ais, solent_ais
from ctxmodels.geo.plane import lonlat_to_local

HEADER = "Time,MMSI,Latitude_degrees,Longitude_degrees,COG_degrees,SOG_knots\n"


def write(tmp_path, rows, header=HEADER):
    path = tmp_path / "log.csv"
    path.write_text(header + "".join(f"{r}\n" for r in rows))
    return path


def test_each_rule(tmp_path):
    rows = [
        "2016-01-12 13:00:10,2,50.75,-1.10,90,10",
        "2016-01-12 13:00:00,1,50.70,-1.20,0,5",      # out of order in the log
        "2016-01-12 13:00:00,1,50.70,-1.21,0,5",      # same time: dropped (the first is kept)
        "2016-01-12 13:00:10,1,50.7005,-1.20,0,5",
        "2016-01-12 13:00:20,1,50.80,-1.20,0,5",      # an isolated jump of 11 km in 10 s
        "2016-01-12 13:00:30,1,50.7015,-1.20,0,5",
        "2016-01-12 13:20:00,1,50.72,-1.20,0,5",      # after a gap of 19.5 min: a new segment
        "2016-01-12 13:00:20,2,54.80,-1.10,90,10",    # outside the box
        "2016-01-12 13:00:30,2,50.75,-1.0995,90,10",
    ]
    log = read_ais(write(tmp_path, rows), box=(-1.5, 50.5, -0.9, 50.9), origin=(-1.2, 50.7))
    assert log.epoch == dt.datetime(2016, 1, 12, 13, 0, 0)
    assert log.origin == (-1.2, 50.7)
    assert log.dropped == {"outside box": 1, "duplicate time": 1, "isolated jump": 1,
                           "not a position": 0}
    one, two = log.trajectories
    assert (one.mmsi, two.mmsi) == (1, 2)
    assert one.times.tolist() == [0.0, 10.0, 30.0, 1200.0]
    assert one.segments == ((0, 3), (3, 4))
    expected = lonlat_to_local([(-1.20, 50.70), (-1.20, 50.7005), (-1.20, 50.7015), (-1.20, 50.72)],
                               (-1.2, 50.7))
    assert np.allclose(one.positions, expected, atol=1e-9)
    assert np.allclose(one.speed, 5 * KNOT)
    # linear between a segment's reports, NaN in the gap, before and after
    at = one.position_at([5.0, 20.0, 600.0, 1200.0, 1300.0, -1.0])
    assert np.allclose(at[0], (expected[0] + expected[1]) / 2)
    assert np.allclose(at[1], expected[1] + (expected[2] - expected[1]) / 2)
    assert np.isnan(at[2:3]).all() and np.allclose(at[3], expected[3]) and np.isnan(at[4:]).all()
    velocity = one.velocity_at([5.0, 30.0])
    assert np.allclose(velocity[0], (expected[1] - expected[0]) / 10)
    assert np.allclose(velocity[1], (expected[2] - expected[1]) / 20)
    assert two.times.tolist() == [10.0, 30.0] and two.segments == ((0, 2),)


def test_default_origin_is_the_box_centre_else_the_mean(tmp_path):
    path = write(tmp_path, ["2016-01-12 13:00:00,1,50.0,-1.0,0,0", "2016-01-12 13:00:01,2,51.0,-2.0,0,0"])
    assert read_ais(path, box=(-3, 49, -1, 52)).origin == (-2.0, 50.5)
    assert read_ais(path).origin == (-1.5, 50.5)


@pytest.mark.parametrize("rows, header, message", [
    ([], HEADER, "holds no reports"),
    (["x"], "Time,MMSI\n", "lacks the column"),
    (["2016-01-12 13:00:00,abc,50,-1,0,0"], HEADER, "line 2: not an AIS report"),
    (["yesterday,1,50,-1,0,0"], HEADER, "line 2"),
    (["2016-01-12 13:00:00,1,50"], HEADER, "line 2"),
])
def test_malformed_logs_are_named(tmp_path, rows, header, message):
    with pytest.raises(ValueError, match=f"source: .*{message}"):
        read_ais(write(tmp_path, rows, header))


def test_what_a_receiver_garbles(tmp_path):
    rows = ["2016-01-12 13:00:00,1,50.70,-1.20,0,5", "2016-01-12 13:00:10,1,95.0,-1.20,0,5",
            "2016-01-12 13:00:20,1,nan,-1.20,0,5", "2016-01-12 13:00:30,1,50.70,181,0,5"]
    path = tmp_path / "log.csv"
    path.write_bytes(b"\xef\xbb\xbf" + (HEADER + "".join(f"{r}\n" for r in rows)).encode())  # a BOM
    log = read_ais(path)
    assert log.dropped["not a position"] == 3 and len(log.trajectories[0].times) == 1
    # every position garbled and nothing to place the plane by
    with pytest.raises(ValueError, match="source: .* holds no report with a position"):
        read_ais(write(tmp_path, ["2016-01-12 13:00:00,1,nan,-1.2,0,5"]))
    # a box that keeps nothing gives no trajectories
    assert read_ais(path, box=(10, 10, 11, 11)).trajectories == ()
    with pytest.raises(ValueError, match="source: .*line 2: not an AIS report"):
        read_ais(write(tmp_path, ["2016-01-12 13:00:00,99999999999999999999,50,-1,0,0"]))
    bad = tmp_path / "latin1.csv"
    bad.write_bytes(HEADER.encode() + b"2016-01-12 13:00:00,1,50,-1,0,0 \xe9\xff\n")
    with pytest.raises(ValueError, match="source: .* is not UTF-8"):
        read_ais(bad)
    with pytest.raises(TypeError, match="source: expected a file path"):
        read_ais(None)
    # course and speed "not available": the position still counts
    log = read_ais(write(tmp_path, ["2016-01-12 13:00:00,1,50.7,-1.2,,",
                                    "2016-01-12 13:00:05,1,50.7,-1.2,nan,3"]))
    assert len(log.trajectories[0].times) == 2 and np.isnan(log.trajectories[0].course).all()


def test_times_are_numbers(tmp_path):
    trajectory = read_ais(write(tmp_path, ["2016-01-12 13:00:00,1,50.7,-1.2,0,5",
                                           "2016-01-12 13:00:10,1,50.71,-1.2,0,5"])).trajectories[0]
    assert trajectory.position_at(5.0).shape == (1, 2)
    assert np.isnan(trajectory.position_at([np.nan])).all()
    for t in ("5", [[1.0, 2.0]], [True], np.datetime64("2016-01-12"), None):
        with pytest.raises(TypeError, match="t: expected seconds"):
            trajectory.position_at(t)
        with pytest.raises(TypeError, match="t: expected seconds"):
            trajectory.velocity_at(t)


def test_bad_arguments_are_named(tmp_path):
    path = write(tmp_path, ["2016-01-12 13:00:00,1,50,-1,0,0"])
    with pytest.raises(FileNotFoundError, match="source: no such file"):
        read_ais(tmp_path / "missing.csv")
    with pytest.raises(ValueError, match="max_gap"):
        read_ais(path, max_gap=0)
    with pytest.raises(ValueError, match="max_speed"):
        read_ais(path, max_speed=-1)
    with pytest.raises(ValueError, match="box"):
        read_ais(path, box=(0, 0, -1, 1))
    with pytest.raises((TypeError, ValueError), match="origin"):
        read_ais(path, origin=(0, 100))


def test_the_solent_log():
    box = (-1.6, 50.55, -0.7, 50.95)
    log = solent_ais(box)
    assert log.epoch == dt.datetime(2016, 1, 12, 13, 2, 11, 218000)
    assert len(log.trajectories) == 91
    kept = sum(len(t.times) for t in log.trajectories)
    # 18,623 reports: one wild position (54.8 deg E) and six others outside the box
    assert kept + sum(log.dropped.values()) == 18623
    assert log.dropped["outside box"] == 7
    for trajectory in log.trajectories:
        assert np.all(np.diff(trajectory.times) > 0)
        assert np.all(np.abs(trajectory.positions) < 40e3)
        gaps = [trajectory.times[b] - trajectory.times[b - 1] for _, b in trajectory.segments[:-1]]
        assert all(g > 300.0 for g in gaps)
    last = max(t.times[-1] for t in log.trajectories)
    assert 83 * 60 < last < 85 * 60  # 13:02 to 14:26
