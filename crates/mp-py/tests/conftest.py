"""Shared fixtures: the `mp` binary, the shared data folder, a procedural track."""

import os
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


def _data_dir():
    if os.environ.get("MP_NO_SHARED_DATA", "") not in ("", "0"):
        return None
    env = os.environ.get("MP_DATA_DIR")
    if env and pathlib.Path(env).is_dir():
        return pathlib.Path(env)
    d = ROOT.parent / "shared" / "data"
    return d if d.is_dir() else None


@pytest.fixture(scope="session")
def mp_bin():
    """The `mp` binary of the same build (MP_BIN, else target/debug/mp)."""
    p = pathlib.Path(os.environ.get("MP_BIN", ROOT / "target" / "debug" / "mp"))
    if not p.is_file():
        pytest.skip(f"the mp binary was not found at {p} (set MP_BIN)")
    return p


def skip_test(test, needs, why):
    """Skips the running test because `needs` (a shared data file, a tool) is missing: prints
    `skipped: {test} needs {needs}` to stderr and appends `{test}\t{needs}` to the file named by
    MP_SKIP_LOG when set (one write per line, as the Rust tests' `mp_geom::skip_test`)."""
    print(f"skipped: {test} needs {needs}", file=sys.stderr)
    log = os.environ.get("MP_SKIP_LOG")
    if log:
        try:
            with open(log, "a", encoding="utf-8") as f:
                f.write(f"{test}\t{needs}\n")
        except OSError:
            pass
    pytest.skip(why)


@pytest.fixture
def skip_needs(request):
    """A function skipping the running test because something it needs (a tool) is missing,
    logging the skip to MP_SKIP_LOG."""
    return lambda needs, why: skip_test(request.node.nodeid, needs, why)


@pytest.fixture
def data(request):
    """A function giving the path of a shared data file, or skipping the test (and logging the
    skip to MP_SKIP_LOG)."""
    d = _data_dir()

    def get(rel):
        if d is None or not (d / rel).exists():
            skip_test(request.node.nodeid, str(rel), f"shared data file `{rel}` not found (../shared/data or MP_DATA_DIR)")
        return d / rel

    return get


@pytest.fixture(scope="session")
def performer(tmp_path_factory, mp_bin):
    """The procedural performer as a track file (made by `mp performer`)."""
    p = tmp_path_factory.mktemp("perf") / "performer.npz"
    subprocess.run([str(mp_bin), "performer", "-o", str(p)], check=True, capture_output=True)
    return p
