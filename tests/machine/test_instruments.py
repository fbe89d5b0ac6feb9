"""A probed sphere, the R-test and mixed identification (issue 27 part 2): B-axis location
errors come back from 1 um-noisy sphere probing at 12 rotary positions within 2 um and 10 urad;
tracker + sphere is never worse than either alone; observation files of each kind; `machine
check --observations` and `machine identify` on a mix."""

import json
import subprocess
import sys

import numpy as np
import pytest

from gagekit.errors import DegenerateGeometryError, FileFormatError, InvalidInputError
from gagekit.machine import Truth, load_machine, simulate
from gagekit.machine.frame import frame_columns
from gagekit.machine.instruments import InstrumentObservations, identify_mixed, instrument_view, read_instrument
from gagekit.machine.model import example_machine_path
from gagekit.machine.simulate_instruments import simulate_sphere

SPHERE = np.array([150.0, 400.0, 250.0])  # table frame, mm: 400 mm above the B axis origin
POSITIONS = np.arange(12) * 30.0
LOCATION = {"EXOB": 0.015, "EZOB": -0.010, "EAOB": 20e-6, "ECOB": -30e-6}


@pytest.fixture(scope="module")
def machine():
    return load_machine(example_machine_path())


def _sphere_obs(c, sigma=0.001, ids=None):
    return InstrumentObservations("sphere", c, None, np.zeros(len(c), int) if ids is None else ids, None, sigma)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_b_axis_location_errors_from_sphere_probing(machine, seed):
    c = simulate_sphere(machine, "B", POSITIONS, SPHERE, {"W": -500.0}, LOCATION, noise_um=1.0, seed=seed)
    res = identify_mixed(machine, [_sphere_obs(c)])
    assert res.unknowns == "location"
    loc = res.location
    assert not any("value" in loc[k] for k in ("EYOB", "EBOB"))  # along the axis, about the axis: unseen
    for k, v in LOCATION.items():
        err = abs(loc[k]["value"] - v)
        assert err <= (0.002 if k[1] in "XYZ" else 10e-6), (k, loc[k], v)
        assert loc[k]["std"] > 0
    assert 0.5 < res.instruments[0]["residual_rms_um"] < 1.5


def test_noise_free_sphere_gives_them_exactly(machine):
    c = simulate_sphere(machine, "B", POSITIONS, SPHERE, {"W": -500.0}, LOCATION)
    loc = identify_mixed(machine, [_sphere_obs(c)]).location
    for k, v in LOCATION.items():
        assert abs(loc[k]["value"] - v) < 1e-8 * (1 if k[1] in "XYZ" else 1e-3), k


def _rms_prediction(machine, cal, truth, test, st):
    """RMS (um) of predicted minus true volumetric error over ``test``, rigid motion removed."""
    from gagekit.machine import predict

    p_nom = machine.nominal(test)
    diff = (predict(machine, cal, test, structure=st) - (machine.positions(test, truth.parameters) - p_nom)).reshape(-1)
    f = frame_columns(p_nom)
    coef, *_ = np.linalg.lstsq(f, diff, rcond=None)
    r = (diff - f @ coef).reshape(-1, 3)
    return 1e3 * float(np.sqrt((r**2).sum(axis=1).mean()))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_mixed_is_never_worse_than_either_alone(machine, seed):
    st = machine.structure()
    truth = Truth.random(machine, seed=seed)
    tracker = simulate(machine, truth, machine.sample_commands(120, seed=seed + 1), seed=seed + 11)
    t_obs = InstrumentObservations("tracker", tracker.commands, tracker.measured, sigma=0.0089)
    spheres = []
    for k, s in enumerate([SPHERE, np.array([-200.0, 900.0, -150.0])]):
        c = simulate_sphere(machine, "B", POSITIONS, s, {"W": -500.0}, {}, noise_um=1.0, seed=seed + 20 + k, params=truth.parameters)
        spheres.append(_sphere_obs(c, ids=np.full(len(c), k)))
    test = machine.sample_commands(500, seed=seed + 99)
    alone_t = identify_mixed(machine, [t_obs], unknowns="groups")
    alone_s = identify_mixed(machine, spheres)
    mixed = identify_mixed(machine, [t_obs] + spheres)
    rms = {name: _rms_prediction(machine, r.calibration, truth, test, st) for name, r in
           (("tracker", alone_t), ("sphere", alone_s), ("mixed", mixed))}
    assert rms["mixed"] <= rms["tracker"] * 1.0001 and rms["mixed"] <= rms["sphere"], rms
    # the information adds: every location error and group the tracker sees is at least as
    # certain with the sphere cycles added
    for k, v in alone_t.location.items():
        if "std" in v:
            assert mixed.location[k]["std"] <= v["std"] * (1 + 1e-9), k
    for k, v in alone_t.groups.items():
        if "std" in v:
            assert mixed.groups[k]["std"] <= v["std"] * (1 + 1e-9), k


def test_views_per_instrument(machine):
    v = instrument_view(machine, ["tracker", "sphere", "rtest", "ballbar"])
    assert set(v) == {"tracker", "sphere", "rtest", "ballbar", "combined"}
    assert 0 < len(v["ballbar"]["groups_seen"]) < len(v["tracker"]["groups_seen"])  # one circle per plane, one place
    for k in ("sphere", "rtest"):
        assert set(v[k]["location_errors_seen"]) == {"EXOB", "EZOB", "EAOB", "ECOB"}
        assert len(v[k]["groups_seen"]) < len(v["tracker"]["groups_seen"])
    assert len(v["combined"]["groups_seen"]) >= len(v["tracker"]["groups_seen"])


def test_rtest_sees_location_errors(machine):
    """R-test (ISO 10791-6 style): the controller puts the nominal ball on the nest while B
    turns; three sensors on the table read the actual ball. The actual ball follows the
    displaced B axis: p = R_true(B) (p_base - e) + e (geometry, not the model's parameters)."""
    from gagekit._rotation import rotation_from_vector

    c = simulate_sphere(machine, "B", POSITIONS, SPHERE, {"W": -500.0}, {})  # nominal ball on the nest
    e = np.array([LOCATION["EXOB"], 0.0, LOCATION["EZOB"]])
    w = np.array([LOCATION["EAOB"], 0.0, LOCATION["ECOB"]])
    axis = rotation_from_vector(w) @ np.array([0.0, 1.0, 0.0])
    d = np.array([[1.0, 0, 0], [0, 0.6, 0.8], [0, -0.8, 0.6]])
    readings = []
    for row in c:
        base = row.copy()
        base[0] = 0.0
        p_base = machine.nominal(base[None, :])[0]
        p = rotation_from_vector(axis * np.radians(row[0])) @ (p_base - e) + e
        readings.append(d @ (p - SPHERE) + 0.0123)  # the sensors' zeros are unknown
    obs = InstrumentObservations("rtest", c, np.array(readings), None, d, 0.0005)
    loc = identify_mixed(machine, [obs]).location
    for k, v in LOCATION.items():
        assert abs(loc[k]["value"] - v) < (1e-5 if k[1] in "XYZ" else 1e-8), (k, loc[k])  # first order: 0.01 um


def test_files_and_cli(machine, tmp_path):
    c = simulate_sphere(machine, "B", POSITIONS, SPHERE, {"W": -500.0}, LOCATION, noise_um=1.0, seed=5)
    lines = ["# kind = sphere", "# sigma_um = 1.0", ",".join(machine.joint_names + ["sphere"])]
    lines += [",".join(repr(float(v)) for v in row) + ",0" for row in c]
    f = tmp_path / "sphere.csv"
    f.write_text("\n".join(lines) + "\n")
    obs = read_instrument(f, machine)
    assert obs.kind == "sphere" and obs.sigma == pytest.approx(0.001) and len(obs) == 12
    for text, exc in (("# kind = laser\nB,X,Z,Y,W\n0,0,0,0,0\n", FileFormatError),
                      ("# kind = sphere\nB,X,Z,Y,W,x\n0,0,0,0,0,1\n", FileFormatError),
                      ("# kind = sphere\n# sigma_um = -1\nB,X,Z,Y,W\n0,0,0,0,0\n", InvalidInputError),
                      ("# kind = rtest\n# directions = 1 0 0; 1 0 0; 0 0 1\nB,X,Z,Y,W,d1,d2,d3\n0,0,0,0,0,0,0,0\n", InvalidInputError)):
        (tmp_path / "bad.csv").write_text(text)
        with pytest.raises(exc):
            read_instrument(tmp_path / "bad.csv", machine)
    cli = lambda *a: subprocess.run([sys.executable, "-m", "gagekit", "machine", *map(str, a)], capture_output=True, text=True)  # noqa: E731
    mf = example_machine_path()
    r = cli("identify", mf, f, "--json", "--out", tmp_path / "cal.json")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert abs(d["location_errors"]["EXOB"]["value"] - 0.015) < 0.002 and d["location_errors"]["EYOB"] == {"seen": False}
    cal = json.loads((tmp_path / "cal.json").read_text())
    assert cal["method"].startswith("mixed")
    r = cli("check", mf, "--observations", "sphere", "--json")
    assert r.returncode == 0, r.stderr
    assert "EXOB" in json.loads(r.stdout)["instruments"]["sphere"]["location_errors_seen"]
    r = cli("check", mf, "--observations", "laser")
    assert r.returncode == 2 and r.stderr.startswith("gagekit: error: ") and len(r.stderr.splitlines()) == 1


def test_kinematics_export(machine, tmp_path):
    from gagekit.machine.export_kinematics import export_kinematics

    c = simulate_sphere(machine, "B", POSITIONS, SPHERE, {"W": -500.0}, LOCATION)
    cal = identify_mixed(machine, [_sphere_obs(c)]).calibration
    res = export_kinematics(machine, cal, tmp_path / "kin.txt", at={"W": -500.0}, stamp="test")
    (b,) = res.axes
    # the X and Z joints move the tool along +x and +z: the axis line moves by EXOB, EZOB
    assert b.point["X"] - b.nominal_point["X"] == pytest.approx(LOCATION["EXOB"], abs=1e-8)
    assert b.point["Z"] - b.nominal_point["Z"] == pytest.approx(LOCATION["EZOB"], abs=1e-8)
    assert b.direction[0] == pytest.approx(-LOCATION["ECOB"], abs=1e-10) and b.direction[2] == pytest.approx(LOCATION["EAOB"], abs=1e-10)
    hal = (tmp_path / "kin_linuxcnc.hal").read_text()
    setp = {ln.split()[1]: float(ln.split()[2]) for ln in hal.splitlines() if ln.startswith("setp")}
    assert setp["xyzbc-trt-kins.x-offset"] == pytest.approx(b.point["X"], abs=1e-6)
    assert setp["xyzbc-trt-kins.z-offset"] == pytest.approx(b.point["Z"], abs=1e-6)
    tab = (tmp_path / "kin_heidenhain.tab").read_text().splitlines()
    trans = [ln.split() for ln in tab if ln.split()[:2] == ["0", "Trans"]][0]
    assert float(trans[2]) == pytest.approx(b.point["X"], abs=1e-6) and float(trans[7]) == pytest.approx(np.degrees(LOCATION["ECOB"]), abs=1e-7)
    sie = (tmp_path / "kin_siemens.txt").read_text()
    assert "$MC_TRAFO5_PART_OFFSET_1[0]=" in sie and "$MC_TRAFO5_AXIS1_1[1]=" in sie
    cli = lambda *a: subprocess.run([sys.executable, "-m", "gagekit", "machine", *map(str, a)], capture_output=True, text=True)  # noqa: E731
    cal.save(tmp_path / "cal.json")
    r = cli("export", example_machine_path(), tmp_path / "cal.json", "--format", "kinematics", "--out", tmp_path / "k.txt", "--at", "W=-500", "--json")
    assert r.returncode == 0, r.stderr
    assert len(json.loads(r.stdout)["files"]) == 3


def test_ballbar_run_as_an_observation(machine, tmp_path):
    """A ballbar file with plane, radius and centre joints joins the identification: alone it
    sees little at one place (reported honestly), with tracker data it sharpens the XY
    squareness and the X, Y scale groups; backlash and servo drop out (both directions averaged)."""
    from gagekit.machine.simulate_instruments import simulate_ballbar

    truth = Truth.random(machine, seed=4)
    at = np.array([0.0, 0.0, 1500.0, 1400.0, -500.0])
    run = simulate_ballbar(machine, truth.parameters, "XY", 150.0, at, points=360, backlash={"X": 0.004}, lag={"Y": 0.001},
                           noise_um=0.1, seed=4)
    lines = ["# kind = ballbar", "# plane = XY", "# radius = 150", "# at = B=0,X=0,Z=1500,Y=1400,W=-500", "# sigma_um = 0.1",
             "angle_deg,deviation_um,direction"]
    lines += [f"{float(a)!r},{float(d)!r},{'ccw' if s > 0 else 'cw'}" for a, d, s in zip(run.angles_deg, run.deviations_um, run.directions)]
    f = tmp_path / "bb.csv"
    f.write_text("\n".join(lines) + "\n")
    bb = read_instrument(f, machine)
    assert bb.kind == "ballbar" and len(bb) == 361  # 360 averaged angles and the centre
    alone = identify_mixed(machine, [bb])
    assert alone.unknowns == "groups" and alone.instruments[0]["residual_rms_um"] < 0.5  # backlash, servo gone
    tracker = simulate(machine, truth, machine.sample_commands(120, seed=5), seed=6)
    t_obs = InstrumentObservations("tracker", tracker.commands, tracker.measured, sigma=0.0089)
    t_only = identify_mixed(machine, [t_obs])
    mixed = identify_mixed(machine, [t_obs, bb])
    sq = next(k for k in t_only.groups if k.startswith("T2.alpha"))
    assert mixed.groups[sq]["std"] < 0.9 * t_only.groups[sq]["std"]  # 13.2 -> 11.1 urad: one circle, one place
    true = truth.group_values(machine)[sq]
    assert abs(mixed.groups[sq]["value"] - true) < 3 * mixed.groups[sq]["std"]
    (tmp_path / "bad.csv").write_text("# kind = ballbar\n# plane = XY\nangle_deg,deviation_um,direction\n0,1,cw\n")
    with pytest.raises(FileFormatError):
        read_instrument(tmp_path / "bad.csv", machine)
    for at, msg in (("B=0,X=0,Z=1500,Y=1400,W=-500,Q=1", "'Q' is not a joint"), ("B=0,X=0,Z=1500,Y=1400", "missing W")):
        (tmp_path / "bad.csv").write_text(f.read_text().replace("B=0,X=0,Z=1500,Y=1400,W=-500", at))
        with pytest.raises(FileFormatError, match=msg):  # an unknown joint was dropped silently
            read_instrument(tmp_path / "bad.csv", machine)


def test_design_for_instruments(machine, tmp_path):
    from gagekit.machine.instrument_design import design_instrument

    same = "\n".join(["# kind = sphere", ",".join(machine.joint_names + ["sphere"])] + ["0,150,1512,400,-500,0"] * 12)
    (tmp_path / "same.csv").write_text(same + "\n")
    with pytest.raises(DegenerateGeometryError, match="see none of the location errors"):  # was exit 0, all "not seen"
        identify_mixed(machine, [read_instrument(tmp_path / "same.csv", machine)])
    with pytest.raises(InvalidInputError, match="'Q' is not a joint"):  # was ignored silently
        design_instrument(machine, "sphere", 12, at={"W": -500.0, "Q": 1.0})
    d = design_instrument(machine, "sphere", 12, at={"W": -500.0})
    assert len(d["positions"]) == 12 and set(d["unknowns"]) == {"sphere x", "sphere y", "sphere z", "EXOB", "EZOB", "EAOB", "ECOB"}
    # the I-optimal positions identify the location errors at least as well as 12 even ones
    from gagekit.machine.instruments import identify_mixed as ident

    def std(pos):
        c = simulate_sphere(machine, "B", np.asarray(pos), SPHERE, {"W": -500.0}, {})
        loc = ident(machine, [_sphere_obs(c)]).location
        return sum(loc[k]["std"] ** 2 * (1e6 if k[1] in "XYZ" else 1e12) for k in LOCATION)

    d2 = design_instrument(machine, "sphere", 12, sphere=SPHERE, at={"W": -500.0})
    assert std(d2["positions"]) <= std(POSITIONS) * 1.05
    cli = lambda *a: subprocess.run([sys.executable, "-m", "gagekit", "machine", *map(str, a)], capture_output=True, text=True)  # noqa: E731
    r = cli("design", example_machine_path(), "--instrument", "sphere", "--points", 8, "--at", "W=-500", "--out", tmp_path / "p.csv", "--json")
    assert r.returncode == 0, r.stderr
    assert read_instrument(tmp_path / "p.csv", machine).kind == "sphere"
    r = cli("design", example_machine_path(), "--instrument", "ballbar", "--points", 5, "--at", "W=-500", "--out", tmp_path / "b.csv")
    assert r.returncode == 0 and "ballbar plan" in r.stdout, r.stderr
    r = cli("design", example_machine_path(), "--instrument", "laser", "--out", tmp_path / "x.csv")
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1


def test_track_sphere_cycles(machine, tmp_path):
    """Daily thermal tracking with a probing cycle: EXOB drifts 3 um per hour, EAOB 4 urad per
    hour; four cycles of 12 probes with 0.5 um noise give the drift back."""
    rows = []
    for k in range(4):
        loc = {**LOCATION, "EXOB": LOCATION["EXOB"] + 0.003 * k, "EAOB": LOCATION["EAOB"] + 4e-6 * k}
        c = simulate_sphere(machine, "B", POSITIONS, SPHERE, {"W": -500.0}, loc, noise_um=0.5, seed=40 + k)
        rows += [[k + 1, *r, float(k), 20.0 + k] for r in c]
    lines = ["# kind = sphere", ",".join(["cycle", *machine.joint_names, "time", "temp_spindle"])]
    lines += [",".join(repr(float(v)) for v in r) for r in rows]
    f = tmp_path / "cycles.csv"
    f.write_text("\n".join(lines) + "\n")
    cli = lambda *a: subprocess.run([sys.executable, "-m", "gagekit", "machine", *map(str, a)], capture_output=True, text=True)  # noqa: E731
    r = cli("track", example_machine_path(), f, "--json", "--report", tmp_path / "rep")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert len(d["cycles"]) == 4 and d["cycles"][3]["drift"]["EXOB"] == pytest.approx(0.009, abs=0.002)
    assert d["trend"]["EXOB"]["slope"] == pytest.approx(0.003, abs=0.001) and d["trend"]["EXOB"]["per"] == "hour"
    assert d["trend"]["EAOB"]["slope"] == pytest.approx(4e-6, abs=2e-6)
    assert (tmp_path / "rep" / "track.json").is_file()
    r = cli("track", example_machine_path(), f)
    assert r.returncode == 0 and "trend EXOB" in r.stdout, r.stderr
    r = cli("track", example_machine_path(), f, "--history", tmp_path / "h.sqlite")
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1
