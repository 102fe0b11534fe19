"""Track formats of other tools, cross-checked with those tools through the `mp` binary: Parquet
with pandas / pyarrow, pose-format `.pose` with the `pose_format` package and C3D with the `c3d`
package, each both ways. Needs no build of the Python extension (the `mp` binary of MP_BIN or
target/debug/mp)."""

import io
import json
import subprocess

import numpy as np
import pytest


def run_cli(mp_bin, *args):
    out = subprocess.run([str(mp_bin), *map(str, args)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out.stdout


def need(module, skip_needs):
    """The module, or the test skipped (and the skip logged) when it is not installed."""
    try:
        return __import__(module, fromlist=["_"])
    except ImportError:
        skip_needs(module, f"{module} is not installed (bash scripts/python.sh installs it)")


def npz_track(path):
    """positions (T, J, D), confidence (T, J), fps, joint names of an `mp` npz track."""
    z = np.load(path)
    return z["positions"], z["confidence"], float(z["fps"]), [str(j) for j in z["joints"]]


@pytest.fixture(scope="module")
def performer_files(tmp_path_factory, mp_bin):
    """The procedural performer (2D, COCO-17, 30 fps) as `mp` writes it: npz, Parquet, `.pose`."""
    d = tmp_path_factory.mktemp("formats")
    for ext in ["npz", "parquet", "pose"]:
        run_cli(mp_bin, "performer", "-o", d / f"p.{ext}")
    return d


def test_parquet_written_by_mp_reads_in_pandas(performer_files, skip_needs):
    pd = need("pandas", skip_needs)
    pq = need("pyarrow.parquet", skip_needs)
    pos, conf, fps, joints = npz_track(performer_files / "p.npz")
    t, j, d = pos.shape
    df = pd.read_parquet(performer_files / "p.parquet")
    assert list(df.columns) == ["frame", "time", "joint", "x", "y", "confidence"]
    assert len(df) == t * j
    assert df["frame"].dtype == np.int64 and df["x"].dtype == np.float64
    np.testing.assert_array_equal(df["frame"].to_numpy().reshape(t, j), np.repeat(np.arange(t), j).reshape(t, j))
    assert list(df["joint"][:j]) == joints
    np.testing.assert_allclose(df["time"].to_numpy(), df["frame"].to_numpy() / fps, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(df["confidence"].to_numpy().reshape(t, j), conf)
    found = conf > 0
    for k, axis in enumerate("xy"):
        v = df[axis].to_numpy().reshape(t, j)
        np.testing.assert_array_equal(v[found], pos[..., k][found])
        assert np.isnan(v[~found]).all()  # a missing joint is null
    meta = pq.read_metadata(performer_files / "p.parquet").metadata
    assert float(meta[b"mp.fps"]) == fps and meta[b"mp.units"] == b"px"


def test_parquet_written_by_pandas_reads_in_mp(performer_files, mp_bin, tmp_path, skip_needs):
    pd = need("pandas", skip_needs)
    need("pyarrow", skip_needs)
    pos, conf, fps, joints = npz_track(performer_files / "p.npz")
    t, j, _ = pos.shape
    frame = np.repeat(np.arange(t), j)
    df = pd.DataFrame(
        {
            "frame": frame,
            "time": frame / fps,
            "joint": np.tile(joints, t),
            "x": pos[..., 0].ravel(),
            "y": pos[..., 1].ravel(),
            "confidence": conf.ravel(),
        }
    )
    # pandas' own file: no `mp` metadata, the rate from the `time` column.
    df.to_parquet(tmp_path / "pandas.parquet")
    # Missing joints as pandas users leave them: NaN coordinates, or no row at all.
    gaps = df.copy()
    gaps.loc[gaps["confidence"] == 0, ["x", "y"]] = np.nan
    gaps.to_parquet(tmp_path / "nan.parquet")
    gaps[gaps["confidence"] > 0].sample(frac=1.0, random_state=0).to_parquet(tmp_path / "rows.parquet")
    # The same program as from the npz: the same positions, confidence, rate and skeleton.
    run_cli(mp_bin, "fit", performer_files / "p.npz", "-o", tmp_path / "npz.txt", "--frame-size", 640)
    want = (tmp_path / "npz.txt").read_text()
    for name in ["pandas", "nan", "rows"]:
        run_cli(mp_bin, "fit", tmp_path / f"{name}.parquet", "-o", tmp_path / f"{name}.txt", "--frame-size", 640)
        assert (tmp_path / f"{name}.txt").read_text() == want, name


def test_pose_written_by_mp_reads_in_pose_format(performer_files, skip_needs):
    need("pose_format", skip_needs)
    from pose_format import Pose

    pos, conf, fps, joints = npz_track(performer_files / "p.npz")
    pose = Pose.read((performer_files / "p.pose").read_bytes())
    assert [c.name for c in pose.header.components] == ["coco17"]
    c = pose.header.components[0]
    assert c.points == joints and c.format == "XYC"
    assert len(c.limbs) == 16
    assert abs(pose.body.fps - fps) < 1e-4
    data = np.asarray(pose.body.data.data)
    assert data.shape == (pos.shape[0], 1, len(joints), 2)
    found = conf > 0
    np.testing.assert_allclose(data[:, 0][found], pos[found], atol=1e-3)
    np.testing.assert_allclose(pose.body.confidence[:, 0], conf, atol=1e-7)
    # pose-format masks the missing points by their confidence.
    assert (pose.body.data.mask[:, 0, :, 0] == ~found).all()


def test_pose_written_by_pose_format_reads_in_mp(performer_files, mp_bin, tmp_path, skip_needs):
    need("pose_format", skip_needs)
    from pose_format import Pose
    from pose_format.numpy import NumPyPoseBody
    from pose_format.pose_header import PoseHeader, PoseHeaderComponent, PoseHeaderDimensions

    pos, conf, fps, joints = npz_track(performer_files / "p.npz")
    t, j, _ = pos.shape
    # A face component first: the body component is the one read.
    face = PoseHeaderComponent("FACE_LANDMARKS", ["f0", "f1", "f2"], [(0, 1)], [(255, 255, 255)], "XYC")
    body = PoseHeaderComponent("BODY_17", joints, [(5, 7), (7, 9)], [(0, 255, 0)], "XYC")
    header = PoseHeader(0.2, PoseHeaderDimensions(640, 480), [face, body])
    data = np.concatenate([np.full((t, 1, 3, 2), 7.0), pos[:, None]], axis=2).astype(np.float32)
    confidence = np.concatenate([np.ones((t, 1, 3)), conf[:, None]], axis=2).astype(np.float32)
    buf = io.BytesIO()
    Pose(header, NumPyPoseBody(fps, data, confidence)).write(buf)
    (tmp_path / "pf.pose").write_bytes(buf.getvalue())
    # The same program as from the npz positions rounded to 32-bit floats: `mp stats` of one
    # program against both reads gives the same error.
    run_cli(mp_bin, "fit", performer_files / "p.npz", "-o", tmp_path / "npz.txt", "--frame-size", 640)
    a = json.loads(run_cli(mp_bin, "stats", performer_files / "p.npz", tmp_path / "npz.txt", "--json"))
    b = json.loads(run_cli(mp_bin, "stats", tmp_path / "pf.pose", tmp_path / "npz.txt", "--json"))
    assert (b["n_frames"], b["n_joints"], b["dims"]) == (t, j, 2)
    assert abs(a["kd"] - b["kd"]) < 1e-3, (a["kd"], b["kd"])
    # Its frame size (640 × 480) scales the fit as `--frame-size 640` does, and its rate is read.
    run_cli(mp_bin, "fit", tmp_path / "pf.pose", "-o", tmp_path / "pose.txt")
    fitted = (tmp_path / "pose.txt").read_text()
    want = (tmp_path / "npz.txt").read_text()
    assert fitted.splitlines()[0] == want.splitlines()[0]


def test_c3d_written_by_mp_reads_in_c3d(mp_bin, tmp_path, skip_needs):
    c3d = need("c3d", skip_needs)
    run_cli(mp_bin, "performer", "--3d", "-o", tmp_path / "p3.npz")
    run_cli(mp_bin, "performer", "--3d", "-o", tmp_path / "p3.c3d")
    pos, conf, fps, joints = npz_track(tmp_path / "p3.npz")
    with open(tmp_path / "p3.c3d", "rb") as f:
        r = c3d.Reader(f)
        assert r.point_rate == fps and r.point_used == len(joints)
        assert [label.strip() for label in r.point_labels] == joints
        assert r.get("POINT:UNITS").string_value.strip() == "mm"
        frames = np.array([points for _, points, _ in r.read_frames()])
    assert frames.shape == (pos.shape[0], len(joints), 5)
    np.testing.assert_allclose(frames[..., :3], pos * 1000, atol=1e-3)  # millimetres, 32-bit floats
    assert (frames[..., 3] >= 0).all()  # every point valid


def test_c3d_written_by_c3d_reads_in_mp(mp_bin, tmp_path, skip_needs):
    c3d = need("c3d", skip_needs)
    run_cli(mp_bin, "performer", "--3d", "-o", tmp_path / "p3.npz")
    pos, conf, fps, joints = npz_track(tmp_path / "p3.npz")

    def write(path, invalid):
        w = c3d.Writer(point_rate=fps, point_units="mm  ")
        for t in range(pos.shape[0]):
            p = np.zeros((len(joints), 5), np.float32)
            p[:, :3] = pos[t] * 1000
            p[invalid, :3] = 0
            p[invalid, 3] = -1  # the format's invalid point
            w.add_frames([(p, np.zeros((0, 0)))])
        w.set_point_labels(joints)
        with open(path, "wb") as f:
            w.write(f)

    write(tmp_path / "all.c3d", [])
    write(tmp_path / "no_nose.c3d", [0])
    run_cli(mp_bin, "fit", tmp_path / "p3.npz", "-o", tmp_path / "p3.txt")
    a = json.loads(run_cli(mp_bin, "stats", tmp_path / "p3.npz", tmp_path / "p3.txt", "--json"))
    b = json.loads(run_cli(mp_bin, "stats", tmp_path / "all.c3d", tmp_path / "p3.txt", "--json"))
    assert (b["n_frames"], b["n_joints"], b["dims"]) == (pos.shape[0], len(joints), 3)
    assert abs(a["kd"] - b["kd"]) < 1e-6  # metres from millimetres, COCO-17 from the labels
    # Invalid points are missing joints: a never-seen nose.
    out = subprocess.run(
        [str(mp_bin), "fit", str(tmp_path / "no_nose.c3d"), "-o", str(tmp_path / "x.txt"), "--strict-joints"],
        capture_output=True,
        text=True,
    )
    assert out.returncode != 0 and "nose" in out.stderr, out.stderr
