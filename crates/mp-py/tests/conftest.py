"""Shared fixtures: the `mp` binary, the shared data folder, a procedural track."""

import os
import pathlib
import subprocess

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


@pytest.fixture(scope="session")
def data():
    """A function giving the path of a shared data file, or skipping the test."""
    d = _data_dir()

    def get(rel):
        if d is None or not (d / rel).exists():
            pytest.skip(f"shared data file `{rel}` not found (../shared/data or MP_DATA_DIR)")
        return d / rel

    return get


@pytest.fixture(scope="session")
def performer(tmp_path_factory, mp_bin):
    """The procedural performer as a track file (made by `mp performer`)."""
    p = tmp_path_factory.mktemp("perf") / "performer.npz"
    subprocess.run([str(mp_bin), "performer", "-o", str(p)], check=True, capture_output=True)
    return p
