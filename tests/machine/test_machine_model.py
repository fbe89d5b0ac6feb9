"""Machine files, the first-order error model and its structure (Sec. 3.1, Eq. 3.13-3.14)."""


import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import gagekit
from gagekit.errors import ConfigError, FileFormatError, InvalidInputError

from conftest import EXAMPLE_MACHINE

EXAMPLE = EXAMPLE_MACHINE


def test_example_loads_with_52_parameters(machine):
    assert machine.joint_names == ["B", "X", "Z", "Y", "W"]
    assert machine.n_parameters == 52
    names = machine.parameter_names
    assert names[:6] == ["B.alpha.1", "B.beta.1", "B.gamma.1", "B.dx.1", "B.dy.1", "B.dz.1"]
    assert "T1.alpha" in names and "X.dalpha" in names and "W.delta" in names
    assert machine.tool == (0.0, 0.0, -312.035)


def test_rank_32_no_effect_and_groups_of_eq_3_14(structure):
    s = structure
    assert s.rank == 32
    assert set(s.no_effect) == {"T4.alpha", "T5.alpha", "W.dalpha"}
    assert s.rank_gap > 1e6
    by_leader = {g.leader: g.terms for g in s.groups}
    assert by_leader["T2.alpha"] == {"T2.alpha": 1.0, "T3.alpha": 1.0}
    assert by_leader["T1.gamma"] == {"T1.gamma": 1.0, "T2.gamma": 1.0}
    assert by_leader["T3.beta"] == {"T3.beta": 1.0, "T4.beta": 1.0}
    dx = by_leader["T1.dx"]
    assert dx["T5.beta"] == pytest.approx(-312.035, rel=1e-9)  # -r_t beta_5 (Eq. 3.14)
    assert dx["T4.beta"] == pytest.approx(450.0, rel=1e-9)  # this example's T4 offset of -450 mm
    assert all(dx[f"T{i}.dx"] == 1.0 for i in range(1, 6))
    assert by_leader["T1.dy"]["T5.gamma"] == pytest.approx(312.035, rel=1e-9)
    assert set(by_leader["T1.dz"]) == {f"T{i}.dz" for i in range(1, 6)}


def test_groups_span_exactly_the_identifiable_subspace(machine, structure):
    cmds = machine.sample_commands(300, seed=5)
    m = machine.design_matrix(cmds)
    c = structure.coefficients
    # M = M[:, leaders] C, and the rows of C span the row space of M
    assert np.allclose(structure.reduce(m) @ c, m, rtol=0, atol=1e-9 * np.abs(m).max())
    keep = [j for j, n in enumerate(machine.parameter_names) if n not in structure.no_effect]
    assert np.abs(c[:, [j for j in range(52) if j not in keep]]).max() == 0
    norms = np.linalg.norm(m[:, keep], axis=0)
    _, s, vt = np.linalg.svd(m[:, keep] / norms, full_matrices=False)
    assert s[structure.rank - 1] > 1e8 * s[structure.rank]
    scaled_c = c[:, keep] / norms  # g = c.p = (c / norms).(norms p): coefficients on equilibrated columns
    scaled_c /= np.linalg.norm(scaled_c, axis=1, keepdims=True)
    assert np.abs(scaled_c @ vt[structure.rank :].T).max() < 1e-9  # C annihilates the null space
    assert np.linalg.matrix_rank(np.vstack([vt[: structure.rank], scaled_c]), tol=1e-8) == structure.rank
    assert np.linalg.matrix_rank(c) == structure.rank


def test_design_matrix_matches_central_differences_of_exact_chain(machine):
    cmds = machine.sample_commands(20, seed=3)
    m = machine.design_matrix(cmds)
    powers = machine.parameter_length_powers
    fd = np.empty_like(m)
    for j in range(machine.n_parameters):
        h = {0: 1e-1, 1: 1e-5, 2: 1e-7}[powers[j]]
        p = np.zeros(machine.n_parameters)
        p[j] = h
        plus = machine.positions(cmds, p)
        p[j] = -h
        minus = machine.positions(cmds, p)
        fd[:, j] = ((plus - minus) / (2 * h)).reshape(-1)
    assert np.allclose(m, fd, rtol=1e-6, atol=1e-6)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-1e-4, 1e-4), min_size=52, max_size=52), st.integers(0, 10**6))
def test_first_order_model_predicts_exact_chain(params, seed):
    m = gagekit.load_machine(EXAMPLE)
    p = np.array(params)
    p[[12, 13, 14, 22, 23, 24, 32, 33, 34, 42, 43, 44]] *= 1e-3  # angular rates (rad/mm)
    cmds = m.sample_commands(10, seed=seed)
    exact = m.positions(cmds, p) - m.nominal(cmds)
    first = m.volumetric_error(cmds, p)
    # the remainder is second order: |p|^2 * lever
    assert np.abs(exact - first).max() <= 1e-8 * 4000 + 50 * (np.abs(p).max() ** 2) * 4000


def test_nominal_positions_of_known_commands(machine):
    # B = 90 deg turns the spindle-frame point (x, y, z + w - 450 - 312.035) about y
    p = machine.nominal([[90.0, 100.0, 1000.0, 500.0, -300.0]])[0]
    local = np.array([100.0, 500.0, 1000.0 - 300.0 - 450.0 - 312.035])
    assert np.allclose(p, [local[2], local[1], -local[0]], atol=1e-9)


def test_commands_checked(machine):
    with pytest.raises(InvalidInputError, match="row 1 has a non-finite X"):
        machine.design_matrix([[0, 0, 1000, 400, -300], [0, np.nan, 1000, 400, -300]])
    with pytest.raises(InvalidInputError, match=r"columns B, X, Z, Y, W"):
        machine.design_matrix(np.zeros((3, 4)))
    assert machine.design_matrix(np.zeros((0, 5))).shape == (0, 52)
    with pytest.warns(UserWarning, match="X: 1"):
        machine.warn_out_of_range([[0, 1300, 1000, 400, -300]])


BASE = EXAMPLE.read_text()


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda t: t.replace('"B", "T1"', '"B", "Q", "T1"'), "chain: unknown element 'Q' (define it as [joints.Q] or [shapes.Q])"),
        (lambda t: t.replace('type = "rotary"', 'type = "linear"'), "joints.B.type must be \"prismatic\" or \"rotary\", got 'linear'"),
        (lambda t: t.replace("axis = [1.0, 0.0, 0.0]", "axis = [2.0, 0.0, 0.0]"), "joints.X.axis must be a unit vector, its length is 2"),
        (lambda t: t.replace("range = [-1250.0, 1250.0]", "range = [1250.0, -1250.0]"), "joints.X.range: min 1250.0 must be less than max -1250.0"),
        (lambda t: t.replace("fourier_terms = 1 ", "fourier_terms = 0 "), "joints.B.fourier_terms must be an integer from 1 to 64, got 0"),
        (lambda t: t.replace('"W", "T5"]', '"W", "T5", "X"]'), "chain: 'X' appears more than once"),
        (lambda t: t.replace(', "T5"]', "]"), "[shapes.T5] is defined but not listed in chain"),
        (lambda t: t.replace("[tool]", "[spindle]"), "unknown top-level key 'spindle'"),
        (lambda t: t.replace('length_unit = "mm"', 'length_unit = "in"'), 'length_unit must be "mm"'),
        (lambda t: t.replace("offset = [0.0, 0.0, -450.0]", "offset = [0.0, -450.0]"), "shapes.T4.offset must be three finite numbers"),
        (lambda t: t.replace("axis = [0.0, 0.0, 1.0]\nrange = [900.0", "axes = [0.0, 0.0, 1.0]\nrange = [900.0"), "joints.Z: unknown key 'axes'"),
    ],
)
def test_bad_machine_files_say_exactly_what_is_wrong(edit, message):
    text = edit(BASE)
    assert text != BASE
    with pytest.raises(ConfigError) as exc:
        gagekit.parse_machine(text, source="m.toml")
    assert str(exc.value).startswith("m.toml: ")
    assert message in str(exc.value)


def test_unreadable_files(tmp_path):
    with pytest.raises(FileFormatError, match="not found"):
        gagekit.load_machine(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("chain = [")
    with pytest.raises(FileFormatError, match="not valid TOML"):
        gagekit.load_machine(bad)


def test_any_chain_order_and_direction():
    text = """
chain = ["C", "S1", "U", "S2", "V"]
angle_unit = "rad"
[joints.C]
type = "rotary"
axis = [0.0, 0.0, 1.0]
range = [-3.0, 3.0]
fourier_terms = 2
[joints.U]
type = "prismatic"
axis = [0.6, 0.8, 0.0]
range = [0, 500]
[joints.V]
type = "prismatic"
axis = [0.0, 0.0, -1.0]
range = [0, 300]
[shapes.S1]
offset = [100.0, 0.0, 50.0]
[shapes.S2]
offset = [0.0, 20.0, 0.0]
[tool]
offset = [0.0, 30.0, -100.0]
"""
    m = gagekit.parse_machine(text)
    assert m.n_parameters == 12 + 6 + 4 + 6 + 4
    s = m.structure(n=500)
    assert 0 < s.rank < m.n_parameters
    cmds = m.sample_commands(50, seed=1)
    assert np.allclose(s.reduce(m.design_matrix(cmds)) @ s.coefficients, m.design_matrix(cmds), atol=1e-8)


def test_bundled_example_machine_loads():
    bundled = gagekit.machine.example_machine_path()
    assert gagekit.load_machine(bundled).n_parameters == 52


def test_rotary_error_about_its_own_axis_adds_to_the_joint_angle(machine):
    """Eq. 3.5: beta (about the B axis) shifts the angle by beta sin(B/2) (Eq. 3.6), exactly."""
    cmds = machine.sample_commands(30, seed=4)
    b = 2e-4
    p = np.zeros(52)
    p[machine.parameter_names.index("B.beta.1")] = b
    shifted = cmds.copy()
    shifted[:, 0] += np.degrees(b * np.sin(np.radians(cmds[:, 0]) / 2))
    assert np.allclose(machine.positions(cmds, p), machine.nominal(shifted), atol=1e-9)


def test_rotary_tilts_and_shifts_enter_in_the_fixed_frame(machine):
    """Eq. 3.5: alpha, gamma and dx, dy, dz of B act in the table frame, scaled by sin(B/2)."""
    cmds = machine.sample_commands(30, seed=5)
    p_nom = machine.nominal(cmds)
    w = np.sin(np.radians(cmds[:, 0]) / 2)[:, None]
    names = machine.parameter_names
    m = machine.design_matrix(cmds).reshape(-1, 3, 52)
    for name, axis in (("B.alpha.1", 2), ("B.gamma.1", 0)):
        e = np.zeros(3)
        e[axis] = 1.0
        assert np.allclose(m[:, :, names.index(name)], w * np.cross(e, p_nom), atol=1e-9)
    for name, axis in (("B.dx.1", 0), ("B.dy.1", 1), ("B.dz.1", 2)):
        e = np.zeros(3)
        e[axis] = 1.0
        assert np.allclose(m[:, :, names.index(name)], w * e, atol=1e-12)


def test_prismatic_joint_of_eq_3_3(machine):
    """X.delta scales the X travel; X.dalpha bends it by (x^2/2) dalpha along y (Eq. 3.3)."""
    cmds = machine.sample_commands(10, seed=6)
    cmds[:, 0] = 0.0  # B = 0: table and machine frames coincide
    names = machine.parameter_names
    m = machine.design_matrix(cmds).reshape(-1, 3, 52)
    x = cmds[:, 1]
    assert np.allclose(m[:, :, names.index("X.delta")], np.c_[x, 0 * x, 0 * x])
    col = m[:, :, names.index("X.dalpha")]
    # rotation x*dalpha about z of the point beyond X, plus the straightness x^2/2 along y
    beyond = machine.nominal(cmds) - np.c_[x, 0 * x, 0 * x]
    assert np.allclose(col, x[:, None] * np.cross([0, 0, 1.0], beyond) + np.c_[0 * x, x**2 / 2, 0 * x])


@st.composite
def random_machines(draw):
    """Chains of 1-6 elements: shapes with offsets, prismatic and rotary joints on any axes."""
    n = draw(st.integers(1, 6))
    kinds = draw(st.lists(st.sampled_from(["shape", "prismatic", "rotary"]), min_size=n, max_size=n))
    if all(k == "shape" for k in kinds):
        kinds[0] = "prismatic"
    coord = st.floats(-500, 500, allow_nan=False)
    lines, chain = ['angle_unit = "rad"'], []
    body = []
    for i, k in enumerate(kinds):
        name = f"E{i}"
        chain.append(name)
        if k == "shape":
            body.append(f"[shapes.{name}]\noffset = {[draw(coord) for _ in range(3)]}")
        else:
            v = np.array([draw(st.floats(-1, 1)) for _ in range(3)])
            if np.linalg.norm(v) < 0.1:
                v = np.array([0.0, 0.0, 1.0])
            v = (v / np.linalg.norm(v)).tolist()
            rng = "[-3.0, 3.0]" if k == "rotary" else "[-800.0, 800.0]"
            extra = f"\nfourier_terms = {draw(st.integers(1, 3))}" if k == "rotary" else ""
            body.append(f'[joints.{name}]\ntype = "{k}"\naxis = {v}\nrange = {rng}{extra}')
    lines.append(f"chain = {chain}".replace("'", '"'))
    lines += body
    lines.append(f"[tool]\noffset = {[draw(coord) for _ in range(3)]}")
    return gagekit.parse_machine("\n".join(lines) + "\n")


@settings(max_examples=20, deadline=None)
@given(random_machines(), st.integers(0, 1000))
def test_any_chain_design_matrix_matches_central_differences(m, seed):
    cmds = m.sample_commands(4, seed=seed)
    d = m.design_matrix(cmds)
    for j, power in enumerate(m.parameter_length_powers):
        h = {0: 1e-1, 1: 1e-5, 2: 1e-7}[power]
        p = np.zeros(m.n_parameters)
        p[j] = h
        plus = m.positions(cmds, p)
        p[j] = -h
        fd = ((plus - m.positions(cmds, p)) / (2 * h)).reshape(-1)
        # central differences: O(h^2) truncation (relative to the column) plus the round-off
        # of positions of size |p| divided by 2h
        tol = 1e-7 * np.abs(d[:, j]).max() + 50 * np.finfo(float).eps * (np.abs(plus).max() + 1.0) / h
        assert np.abs(d[:, j] - fd).max() < tol, m.parameter_names[j]


@settings(max_examples=25, deadline=None)
@given(random_machines())
def test_any_chain_groups_reproduce_the_design_matrix(m):
    s = m.structure(n=300)
    assert len(s.groups) == s.rank <= m.n_parameters - len(s.no_effect)
    d = m.design_matrix(m.sample_commands(40, seed=3))
    assert np.abs(s.reduce(d) @ s.coefficients - d).max() <= 1e-6 * (np.abs(d).max() + 1)
    for g in s.groups:
        assert g.terms[g.leader] == 1.0
