"""Road files: CSV and ASAM OpenCRG round trips, hand-written files of the published format, bad files, and a
ride on an exported-then-imported road."""

import json
import math
import os
import struct

import numpy as np
import pytest

from identification.comfort.road import FILE_CLASS, road_profile
from identification.comfort.road_files import (read_road, read_road_crg, read_road_csv, write_road_crg,
                                               write_road_csv)
from identification.errors import InputError


@pytest.fixture(scope="module")
def road():
    return road_profile("D", 300.0, 0.01, 5, coherence="class", track_width_m=1.65)


def test_csv_round_trip_is_bit_for_bit_with_the_track_width(tmp_path, road):
    path = write_road_csv(road, tmp_path / "road.csv")
    lines = path.read_text(encoding="utf-8").splitlines()
    header = lines.index("x_m,left_m,right_m")
    assert all(line.startswith("#") for line in lines[:header]) and "# track_width_m = 1.65" in lines
    assert len(lines) - header - 1 == road.x_m.size
    back = read_road_csv(path)
    np.testing.assert_array_equal(back.x_m, road.x_m)
    np.testing.assert_array_equal(back.left_m, road.left_m)
    np.testing.assert_array_equal(back.right_m, road.right_m)
    assert back.track_width_m == 1.65 and back.road_class == FILE_CLASS and back.spacing_m == road.spacing_m
    assert read_road_csv(path, track_width_m=2.0).track_width_m == 2.0


def test_crg_round_trip_is_exact_to_the_printed_14_digits(tmp_path, road):
    path = write_road_crg(road, tmp_path / "road.crg")
    text = path.read_text(encoding="latin-1")
    head, _, data = text.partition("\n" + "$" * 80 + "\n")
    assert head.startswith("$CT\n") and "\n$ROAD_CRG\n" in head and "\n$KD_Definition\n#:LDFI\n" in head
    assert "REFERENCE_LINE_INCREMENT = 0.01" in head and "D:reference line u,m" in head
    assert "D:long section at v = -0.825,m\nD:long section at v = 0.825,m" in head
    assert all(len(line) <= 72 for line in head.splitlines())
    rows = data.splitlines()
    assert len(rows) == road.x_m.size and {len(r) for r in rows} == {60}     # 3 fields of 20 characters
    back = read_road_crg(path)
    printed = lambda a: np.array([float(f"{v:.13e}") for v in a])         # the value as written, 14 digits
    np.testing.assert_array_equal(back.x_m, printed(road.x_m))
    np.testing.assert_array_equal(back.left_m, printed(road.left_m))
    np.testing.assert_array_equal(back.right_m, printed(road.right_m))
    assert back.track_width_m == 1.65
    assert np.max(np.abs(back.left_m - road.left_m)) <= 5e-14 * np.max(np.abs(road.left_m))


# A small OpenCRG file written by hand after the ASAM OpenCRG 1.2 specification: LRFI (10-character reals,
# which may touch: "0.0200000-0.0100000"), five numbered long sections 0.5 m apart from v = -1 m, comments
# by "*" in column 1 and "!" inline, a missing value ("*missing*") in the outermost right section.
HANDMADE_LRFI = """\
$CT                                   ! comment text block
hand-made road: 6 cuts 0.25 m apart, 5 long sections from v = -1 m
$!**********************************************************************
$ROAD_CRG                             ! road parameters
REFERENCE_LINE_START_U   = 10.0
REFERENCE_LINE_END_U     = 11.25
REFERENCE_LINE_INCREMENT = 0.25       ! u step, m
LONG_SECTION_V_RIGHT     = -1.0
LONG_SECTION_V_LEFT      =  1.0
LONG_SECTION_V_INCREMENT =  0.5
$!**********************************************************************
$KD_Definition                        ! data definition
#:LRFI                                ! plain text, reals of 10 characters
D:long section 1,m                    ! v = -1.0
D:long section 2,m                    ! v = -0.5
D:long section 3,m                    ! v =  0.0
D:long section 4,m                    ! v =  0.5
D:long section 5,m                    ! v =  1.0
$!**********************************************************************
* the data rows follow the separator
$$$$$$$$10$$$$$$$$20$$$$$$$$30$$$$$$$$40$$$$$$$$50$$$$$$$$60$$$$$$$$70$$$$$$$$80
 *missing* 0.0100000 0.0000000 0.0200000 0.0300000
 0.0000000 0.0200000-0.0100000 0.0400000 0.0100000
 0.0000000 0.0300000 0.0000000-0.0200000 0.0000000
 0.0000000 0.0000000 0.0000000 0.0000000 0.0000000
 0.0000000-0.0150000 0.0050000 0.0250000-0.0050000
 0.0000000 0.0010000 0.0020000 0.0030000 0.0040000
"""
#: Columns of v = -0.5 m and +0.5 m, read by eye from the rows above.
HANDMADE_RIGHT = [0.01, 0.02, 0.03, 0.0, -0.015, 0.001]
HANDMADE_LEFT = [0.02, 0.04, -0.02, 0.0, 0.025, 0.003]


def test_a_hand_written_lrfi_file_is_read_as_the_specification_says(tmp_path):
    path = tmp_path / "handmade.crg"
    path.write_text(HANDMADE_LRFI, encoding="latin-1")
    r = read_road_crg(path, track_width_m=1.0)               # tracks on the sections at v = ±0.5 m
    assert r.road_class == FILE_CLASS and r.track_width_m == 1.0
    np.testing.assert_allclose(r.x_m, 0.25 * np.arange(6), rtol=0, atol=1e-15)       # u from 10 m, from 0
    np.testing.assert_allclose(r.right_m, HANDMADE_RIGHT, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.left_m, HANDMADE_LEFT, rtol=0, atol=1e-12)
    # tracks 1.5 m apart: v = ±0.75 m, halfway between the sections at 0.5 and 1.0 m
    full = tmp_path / "full.crg"
    full.write_text(HANDMADE_LRFI.replace(" *missing*", " 0.0400000"), encoding="latin-1")
    wide = read_road_crg(full, track_width_m=1.5)
    left_outer = [0.03, 0.01, 0.0, 0.0, -0.005, 0.004]
    right_outer = [0.04, 0.0, 0.0, 0.0, 0.0, 0.0]
    np.testing.assert_allclose(wide.left_m, (np.array(HANDMADE_LEFT) + left_outer) / 2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(wide.right_m, (np.array(HANDMADE_RIGHT) + right_outer) / 2, rtol=0, atol=1e-12)
    # with the value missing, the right track there is refused with its line
    with pytest.raises(InputError, match=r"handmade.crg: line 22: right_m is not a finite number"):
        read_road_crg(path, track_width_m=1.5)


def test_a_hand_written_ldfi_file_wraps_a_row_of_five_channels_over_two_records(tmp_path):
    """LDFI: 20-character doubles, 4 a record; u and four long sections make 5 channels, each row 2 records
    (the second holding one value), the tracks the sections at v = -0.9 and +0.9 m of B = 1.8 m."""
    rows = [(0.0, 1.0, 2.0, 3.0, 4.0), (0.1, -1.5e-3, 2.5e-3, 3.5e-3, -4.5e-3), (0.2, 0.0, 1e-5, -2e-5, 0.0)]
    data = "".join(f"{r[0]:20.12f}{r[1]:20.12e}{r[2]:20.12e}{r[3]:20.12e}\n{r[4]:20.12e}\n" for r in rows)
    text = ("$CT\nfive channels\n$\n$ROAD_CRG\nREFERENCE_LINE_INCREMENT = 0.1\n$\n$KD_Definition\n#:LDFI\n"
            "D:reference line u,m\nD:long section at v = -2.0,m\nD:long section at v = -0.9,m\n"
            "D:long section at v = 0.9,m\nD:long section at v = 2.0,m\n$\n$$$$\n" + data)
    path = tmp_path / "five.crg"
    path.write_text(text, encoding="latin-1")
    r = read_road_crg(path)
    assert r.track_width_m == pytest.approx(1.8)
    np.testing.assert_allclose(r.x_m, [0.0, 0.1, 0.2], rtol=0, atol=1e-15)
    np.testing.assert_allclose(r.right_m, [2.0, 2.5e-3, 1e-5], rtol=1e-12)
    np.testing.assert_allclose(r.left_m, [3.0, 3.5e-3, -2e-5], rtol=1e-12)
    path.write_text(text.rstrip("\n").rsplit("\n", 1)[0] + "\n", encoding="latin-1")     # the last record cut
    with pytest.raises(InputError, match="do not make whole rows"):
        read_road_crg(path)


def test_a_hand_written_binary_krbi_file_is_read(tmp_path):
    """KRBI: big-endian IEEE float32, records of 80 bytes filled one after another, the last padded with NaN;
    three channels (u, two tracks by position) and 9 cuts: 27 values, 2 records, 13 NaN of padding."""
    u = 0.5 * np.arange(9)
    right = 0.001 * np.arange(9) ** 2
    left = -0.002 * np.arange(9)
    values = np.column_stack([u, right, left]).ravel().tolist() + [math.nan] * 13
    head = ("$CT\nbinary test road\n$\n$ROAD_CRG\nREFERENCE_LINE_INCREMENT = 0.5\n$\n$KD_Definition\n#:KRBI\n"
            "D:reference line u,m\nD:long section at v = -0.9,m\nD:long section at v = 0.9,m\n$\n$$$$\n")
    path = tmp_path / "binary.crg"
    path.write_bytes(head.encode("latin-1") + struct.pack(">40f", *values))
    r = read_road_crg(path)
    assert r.track_width_m == pytest.approx(1.8) and r.x_m.size == 9
    np.testing.assert_array_equal(r.right_m, np.float32(right).astype(float))
    np.testing.assert_array_equal(r.left_m, np.float32(left).astype(float))


def test_read_road_picks_the_format_by_suffix(tmp_path, road):
    a = read_road(write_road_csv(road, tmp_path / "r.csv"))
    b = read_road(write_road_crg(road, tmp_path / "r.CRG"))
    np.testing.assert_allclose(a.left_m, b.left_m, rtol=1e-13, atol=0)
    with pytest.raises(InputError, match="must end in .csv or .crg"):
        read_road(tmp_path / "r.txt")


def _ride_on(road, duration_s=20.0):
    from identification.comfort.ride import ride
    from identification.model.tractor import Body
    from tractor_cases import C, K, LOADS, TIRES

    body = Body(TIRES, LOADS, 2.6, pitch=True, roll=True, pivot=False, pitch_index=0.8, roll_index=0.5)
    sets = {"t": (dict(zip(TIRES, K)), dict(zip(TIRES, C)))}
    return ride(body, sets, road=road, speed_m_s=2.0, duration_s=duration_s, seat_x_m=1.4, seat_y=0.3)["t"]


def test_a_ride_on_the_exported_then_imported_road_gives_the_same_a_w(tmp_path):
    from identification.comfort.ride import ROAD_SPACING_M

    generated = road_profile("C", 2.0 * 20.0 + 1.0, ROAD_SPACING_M, 3)
    a_w = _ride_on(generated).comfort.a_w
    for name in ("r.csv", "r.crg"):
        imported = read_road(write_road_csv(generated, tmp_path / name) if name.endswith("csv")
                             else write_road_crg(generated, tmp_path / name))
        run = _ride_on(imported)
        assert run.comfort.a_w == pytest.approx(a_w, rel=1e-6, abs=0), name
        assert run.axes.axes["y"].a_w == pytest.approx(_ride_on(generated).axes.axes["y"].a_w, rel=1e-6), name
    other = road_profile("C", 2.0 * 20.0 + 1.0, ROAD_SPACING_M, 4)        # the check tells roads apart
    assert abs(_ride_on(other).comfort.a_w / a_w - 1) > 1e-3


# ----------------------------------------------------------------------------- the command


def _bad(tmp_path, kind):
    p = tmp_path / ("road.crg" if kind.startswith("crg") else "road.csv")
    x = (0.01 * np.arange(50)).tolist()
    rows = [f"{a!r},{0.001 * i!r},{-0.001 * i!r}" for i, a in enumerate(x)]
    if kind == "missing":
        return tmp_path / "none.csv"
    if kind == "directory":
        p.mkdir()
    elif kind == "fifo":
        os.mkfifo(p)
    elif kind == "csv-header":
        p.write_text("x,left,right\n" + "\n".join(rows) + "\n")
    elif kind == "csv-text":
        rows[7] = "0.07,abc,0.0"
        p.write_text("x_m,left_m,right_m\n" + "\n".join(rows) + "\n")
    elif kind == "csv-nan":
        rows[9] = "0.09,nan,0.0"
        p.write_text("x_m,left_m,right_m\n" + "\n".join(rows) + "\n")
    elif kind == "csv-spacing":
        rows[20] = "0.205,0.0,0.0"
        p.write_text("x_m,left_m,right_m\n" + "\n".join(rows) + "\n")
    elif kind == "csv-cells":
        rows[3] = "0.03,0.0"
        p.write_text("x_m,left_m,right_m\n" + "\n".join(rows) + "\n")
    elif kind == "crg-separator":
        p.write_text("$CT\nno data\n$\n$ROAD_CRG\nREFERENCE_LINE_INCREMENT = 1.0\n$\n")
    elif kind == "crg-increment":
        p.write_text(HANDMADE_LRFI.replace("REFERENCE_LINE_INCREMENT = 0.25", "REFERENCE_LINE_STEP = 0.25"))
    elif kind == "crg-missing":
        p.write_text(HANDMADE_LRFI.replace(" *missing* 0.0100000", " 0.0000000 0.0100000")     # row 1 whole
                     .replace(" 0.0000000-0.0150000 0.0050000", " 0.0000000 *missing* 0.0050000"))      # row 5
    elif kind == "crg-slope":
        p.write_text(HANDMADE_LRFI.replace("$KD_Definition", "$KD_Definition\nD:reference line slope,m/m", 1))
    return p


BAD = {"missing": "no such file", "directory": "is a directory", "fifo": "not a regular file",
       "csv-header": "expected 'x_m,left_m,right_m'", "csv-text": "line 9, column left_m: 'abc' is not a number",
       "csv-nan": "line 11: left_m is not a finite number",
       "csv-spacing": "line 22: position 0.205 m is 50.0% of a step",
       "csv-cells": "line 5: expected 3 cells", "crg-separator": "no '$$$$' line",
       "crg-increment": "needs REFERENCE_LINE_INCREMENT", "crg-missing": "line 26: right_m is not a finite number",
       "crg-slope": "'reference line slope' is not supported"}


@pytest.mark.parametrize("kind", list(BAD))
def test_ride_refuses_a_bad_road_file_in_one_line_exit_2(cli, tmp_path, kind):
    path = _bad(tmp_path, kind)
    r = cli("ride", "--example", "7kmh", "--road-file", path)
    assert r.code == 2 and r.out == ""
    assert r.err.count("\n") == 1 and r.err.startswith(f"cleatfmu: error: {path}: ") and BAD[kind] in r.err, r.err


@pytest.mark.parametrize("args, source", [
    (["--road-file", "r.csv", "--road", "C"], "--road"),
    (["--road-file", "r.csv", "--coherence", "class"], "--coherence"),
    (["--road-file", "r.csv", "--realisations", "3"], "--realisations"),
    (["--save-road", "out.txt"], "out.txt"),
])
def test_ride_road_options_that_do_not_fit_end_in_one_line(cli, tmp_path, args, source):
    r = cli("ride", "--example", "7kmh", *args)
    assert r.code == 2 and r.err.startswith(f"cleatfmu: error: {source}: ") and r.err.count("\n") == 1, r.err


def test_ride_saves_its_road_and_rides_the_saved_road_to_the_same_a_w(cli, tmp_path, example_diagnosis):
    """``ride --save-road`` writes seed's generated road (class coherence here, the first of two realisations);
    ``ride --road-file`` on that file gives every set the same a_w, the class reported as 'file'."""
    saved = tmp_path / "out" / "road.crg"
    common = ("ride", "--example", "7kmh", "--compare", "final", "--duration-s", "10", "--json", "--workers", "1",
              "--body", example_diagnosis)
    first = cli(*common, "--road", "D", "--coherence", "class", "--realisations", "2", "--save-road", saved)
    assert first.code == 0, first.err
    again = cli(*common, "--road-file", saved)
    assert again.code == 0, again.err
    a, b = json.loads(first.out), json.loads(again.out)
    assert a["road"]["class"] == "D" and a["road"]["coherence"] == "class" and a["road"]["realisations"] == 2
    assert b["road"]["class"] == "file" and b["road"]["file"] == str(saved) and b["road"]["realisations"] == 1
    assert b["road"]["length_m"] == pytest.approx(a["road"]["length_m"], rel=1e-12)
    assert b["sets"]["final"]["a_w"] == pytest.approx(a["sets"]["final"]["a_w"], rel=1e-6)
    assert b["sets"]["final"]["expected"]["psd"]["a_w"] is None        # a file road has no model spectrum
