"""The sample files bundled with the package, by name (``gagekit data list``, ``gagekit data
path NAME``): what the README's tour and ``docs/`` run on.

=================  =====================================================================
name               file (under the installed ``gagekit`` package)
=================  =====================================================================
round              ``data/round.csv``: a turned circle, 2-D (``data/make_form_samples.py``)
bore               ``data/bore.csv``: a bored hole, 8 sections
ball               ``data/ball.csv``: a reference ball, upper hemisphere
cone               ``data/cone.csv``: a shaft cone
program            ``data/program.nc``: an NC program for the example machine
machine            ``machine/examples/dissertation-5axis.toml``: the dissertation's 5-axis
                   machine (Eq. 3.1, Table 3.1)
casting            ``data/casting_ok.ply``: a simulated casting scan (``make_castings.py``)
casting-gages      ``data/casting_ok.toml``: its virtual gages (Table 5.1)
casting-short      ``data/casting_short.ply``, ``casting-short-gages``: a casting short of
                   material
bracket            ``data/bracket.ply``: a scanned bracket (``make_bracket.py``)
bracket-part       ``data/bracket.toml``: its drawing (GD&T callouts)
bracket-mesh       ``data/bracket.obj``: its STEP model tessellated, one group per face
grr-study          ``data/grr_study.csv``: a gage R&R study (``make_grr_sample.py``)
cylinder-set1/3    ``data/cylinders/set1.csv``, ``set3.csv``: the dissertation's cylinder
                   data sets (Tables 6.2, 6.4)
iso230-2           ``data/ecmc_axis1_runs.csv``: readings of an ISO 230-2 test of a real axis
                   (the ecmc motion system test report, anderssandstrom/ecmccomgui)
ballbar            ``data/ballbar_xy.csv``: a simulated ballbar run of the example machine,
                   XY, R 150 mm, with ``# kind = ballbar`` lines
                   (``data/make_instrument_samples.py``)
sphere             ``data/sphere_b.csv``: a probed sphere at 12 B positions (``# kind =
                   sphere``)
rtest              ``data/rtest_b.csv``: an R-test of the B axis (``# kind = rtest``)
sphere-cycles      ``data/sphere_cycles.csv``: four sphere probing cycles an hour apart
                   (``machine track``)
roundness          ``data/roundness_profile.csv``: a roundness trace of a shaft, 3600
                   points (``data/make_roundness_samples.py``)
straightness       ``data/straightness_profile.csv``: a 40 mm straightness trace
=================  =====================================================================
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from .errors import ConfigError

__all__ = ["SAMPLES", "data_path", "sample_path"]

#: name -> (path inside the package, one-line description)
SAMPLES: dict[str, tuple[str, str]] = {
    "round": ("data/round.csv", "turned circle, 2-D points x,y (form fit circle)"),
    "bore": ("data/bore.csv", "bored hole, 8 sections (form fit cylinder)"),
    "ball": ("data/ball.csv", "reference ball, upper hemisphere (form fit sphere)"),
    "cone": ("data/cone.csv", "shaft cone, 6 sections (form fit cone)"),
    "program": ("data/program.nc", "NC program for the example machine (machine compensate-nc)"),
    "machine": ("machine/examples/dissertation-5axis.toml", "the dissertation's 5-axis machine (machine ...)"),
    "casting": ("data/casting_ok.ply", "scanned casting (cloud ..., gage check)"),
    "casting-gages": ("data/casting_ok.toml", "virtual gages of the casting (gage check)"),
    "casting-short": ("data/casting_short.ply", "scanned casting short of material"),
    "casting-short-gages": ("data/casting_short.toml", "virtual gages of the short casting"),
    "bracket": ("data/bracket.ply", "scanned bracket (inspect)"),
    "bracket-part": ("data/bracket.toml", "drawing of the bracket, GD&T callouts (inspect)"),
    "bracket-step": ("data/bracket.step", "the bracket's nominal STEP model, named faces (compare) [cad]"),
    "bracket-mesh": ("data/bracket.obj", "the bracket's STEP model tessellated (0.5 um), one OBJ group per face (compare)"),
    "bracket-cad-part": ("data/bracket_cad.toml", "drawing of the bracket on its STEP model: profile of surfaces [cad]"),
    "cylinder-set1": ("data/cylinders/set1.csv", "the dissertation's cylinder data set 1 (Table 6.2)"),
    "cylinder-set3": ("data/cylinders/set3.csv", "the dissertation's cylinder data set 3 (Table 6.4)"),
    "iso230-2": ("data/ecmc_axis1_runs.csv", "ISO 230-2 runs of a real axis (machine iso230-2)"),
    "ballbar": ("data/ballbar_xy.csv", "simulated ballbar run, XY, R 150 mm (machine ballbar, machine identify)"),
    "sphere": ("data/sphere_b.csv", "probed sphere at 12 B positions, '# kind = sphere' (machine identify)"),
    "rtest": ("data/rtest_b.csv", "R-test of the B axis, '# kind = rtest' (machine identify)"),
    "sphere-cycles": ("data/sphere_cycles.csv", "four sphere probing cycles, B axis drifting (machine track)"),
    "grr-study": ("data/grr_study.csv", "gage R&R study, 10 parts x 3 appraisers x 3 trials (stats grr)"),
    "roundness": ("data/roundness_profile.csv", "roundness trace of a shaft, 3600 points, 12 um eccentric (form roundness)"),
    "straightness": ("data/straightness_profile.csv", "straightness trace, 40 mm, 4001 points (form straightness)"),
}


def data_path(name: str) -> Path:
    """Path of a bundled file in ``gagekit/data`` by its file name (the demo's inputs)."""
    return Path(str(resources.files("gagekit") / "data" / name))


def sample_path(name: str) -> Path:
    """Path of the bundled sample ``name`` (see :data:`SAMPLES`); :class:`ConfigError` for a
    name that is not one."""
    key = str(name).strip().lower()
    if key not in SAMPLES:
        raise ConfigError(f"no bundled sample named {name!r}; the samples are: {', '.join(SAMPLES)}")
    return Path(str(resources.files("gagekit").joinpath(SAMPLES[key][0])))
