"""Shared test settings: where the bundled reference data lives; the example machine.

Everything the tests read is inside the repository: the NIST least-squares pairs under
``tests/data/nist-l2`` (public data, see ``tests/data/README.md``), the dissertation's cylinder
sets and the example machine inside the package (runtime data the demo uses too).
"""

import os
import signal
from pathlib import Path

import pytest
from hypothesis import settings

import gagekit
from gagekit.samples import data_path

# Property tests: random examples on a developer's machine (they explore), the same derived
# examples on every CI run (CI=true: a run's verdict does not depend on the draw; a failure
# seen once is seen again). Each test's own max_examples and deadline still apply.
settings.register_profile("ci", derandomize=True, print_blob=True)
settings.register_profile("dev", print_blob=True)
settings.load_profile("ci" if os.environ.get("CI", "").lower() in ("1", "true", "yes") else "dev")

# pytest-xdist's workers ignore SIGINT (the controller takes Ctrl-C), and a child process
# inherits an ignored signal: `gagekit` started by a test would then never see the Ctrl-C the
# interrupt tests send (Python installs its handler only where SIGINT is not ignored). Restore
# the defaults, so children start as they do from a shell.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)
for _sig in (signal.SIGTERM, signal.SIGHUP):
    if signal.getsignal(_sig) is signal.SIG_IGN:
        signal.signal(_sig, signal.SIG_DFL)

ROOT = Path(__file__).resolve().parents[1]
TEST_DATA = ROOT / "tests" / "data"
# NIST ASME B89.4.10 least-squares reference pairs
NIST = TEST_DATA / "nist-l2"
# the dissertation's cylinder data sets 1 and 3 with its reported results (Tables 6.2, 6.4)
SEED_CYLINDERS = data_path("cylinders")
# the dissertation's 5-axis machine (Eq. 3.1, Table 3.1), as bundled in the package
EXAMPLE_MACHINE = gagekit.machine.example_machine_path()


@pytest.fixture(scope="session")
def machine():
    return gagekit.load_machine(EXAMPLE_MACHINE)


@pytest.fixture(scope="session")
def structure(machine):
    return machine.structure()


# real servers (PostgreSQL, Dask LocalCluster) for the store and batch tests: tests/servers.py
from servers import dask_cluster, postgres, postgres_url  # noqa: E402,F401
from castings import casting_set, scans_copy  # noqa: E402,F401


# The longest test files first. `--dist loadfile` hands the files to the workers in collection
# order, so a file that takes minutes (the stub generator's release build, the demo in a fresh
# venv, the bare install) collected last runs alone at the end while the other workers idle;
# started first, it overlaps the many short files. A stable sort: every other file, and the
# tests inside each file, keep their order. Measured in a fresh clone (pytest --durations).
SLOW_FILES_FIRST = (
    "tests/test_stubs.py",
    "tests/report/test_demo.py",
    "tests/test_bare_install.py",
    "tests/cli/test_inspect_cli.py",
    "tests/uncertainty/test_coverage.py",
    "tests/hostile/test_cli_fuzz.py",
)


def pytest_collection_modifyitems(config, items):
    rank = {name: i for i, name in enumerate(SLOW_FILES_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::", 1)[0], len(rank)))
