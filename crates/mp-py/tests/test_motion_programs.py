"""motion_programs against the `mp` command line on the same input: the same
programs and counts, bad input as clear exceptions, the GIL released while
Rust works."""

import json
import pathlib
import pickle
import subprocess
import threading
import time

import numpy as np
import pytest

import motion_programs as mp


def run_cli(mp_bin, *args):
    out = subprocess.run([str(mp_bin), *map(str, args)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_track_arrays_and_round_trips(performer, tmp_path):
    t = mp.read_track(performer)
    assert t.positions.shape == (t.n_frames, t.n_joints, t.dims) == (t.n_frames, 17, 2)
    assert t.confidence.shape == (t.n_frames, 17)
    assert t.skeleton == "coco17" and t.joint_names[0] == "nose"
    assert t.units == "px" and t.fps > 0 and len(t) == t.n_frames
    # numpy in and out.
    u = mp.Track.from_numpy(t.positions, t.fps, confidence=t.confidence, skeleton="coco17")
    np.testing.assert_array_equal(u.positions, t.positions)
    # float32, integers, a transposed (non-contiguous) array and nested lists read the same.
    small = np.round(t.positions[:20])
    for like in (
        small.astype(np.float32),
        small.astype(np.int32),
        np.ascontiguousarray(small.transpose(1, 0, 2)).transpose(1, 0, 2),
        small.tolist(),
    ):
        w = mp.Track.from_numpy(like, t.fps, confidence=t.confidence[:20].astype(np.float32))
        np.testing.assert_array_equal(w.positions, small)
        np.testing.assert_array_equal(w.confidence, t.confidence[:20].astype(np.float32))
    # Pickle (through the binary form) and files.
    v = pickle.loads(pickle.dumps(t))
    np.testing.assert_array_equal(v.positions, t.positions)
    assert v.joint_names == t.joint_names
    t.save(tmp_path / "t.mpt")
    np.testing.assert_array_equal(mp.read_track(tmp_path / "t.mpt").positions, t.positions)


def test_fit_abstract_count_equal_the_cli(performer, mp_bin, tmp_path):
    t = mp.read_track(performer)
    prog = mp.fit(t)
    run_cli(mp_bin, "fit", performer, "-o", tmp_path / "p.txt", "--quiet")
    assert prog.text == (tmp_path / "p.txt").read_text(), "mp.fit and mp fit differ"
    assert prog == mp.Program.read(tmp_path / "p.txt")
    assert prog.n_segments == len(prog.segments) > 10
    x = prog.execute()
    assert x.shape == t.positions.shape and np.isfinite(x).all()
    assert prog.execute(fps=2 * t.fps).shape[0] >= 2 * t.n_frames - 2
    # The abstract program and the counts.
    a = mp.abstract(t)
    run_cli(mp_bin, "abstract", performer, "-o", tmp_path / "a.json", "--quiet")
    assert json.loads(a.to_json()) == json.loads((tmp_path / "a.json").read_text())
    assert a.concrete == prog
    c = mp.count(t)
    cli = json.loads(run_cli(mp_bin, "loops", performer, "--json"))
    reps = cli["repetitions"]
    assert c.total == reps["total"] == 10
    assert [i["count"] for i in c.intervals] == [i["count"] for i in reps["intervals"]] == [4, 3, 3]
    assert c.intervals == reps["intervals"]
    assert c.method == reps["method"] and c.signal == "keypoints"
    # Each interval states the signal it was counted from.
    assert [i["signal"] for i in c.intervals] == ["keypoints"] * 3
    # The program loops are the abstract program's `for` statements, another thing.
    assert a.program_loops == cli["program_loops"]
    assert all(len(l["iteration_frames"]) == l["iterations"] for l in a.program_loops)
    # Free parameters: a C0 program's start poses are the previous segment's ends.
    _, j, d = t.positions.shape
    assert prog.n_numbers - prog.n_params == d * j * (prog.n_segments - 1)
    independent = mp.fit(t, continuity="none")
    assert independent.n_params == independent.n_numbers
    # A fixed λ is honoured.
    assert mp.fit(t, lambda_=400.0).n_segments != prog.n_segments
    # A parameter budget: the same program as `mp fit --budget`, within the budget.
    small = mp.fit(t, budget=0.05)
    run_cli(mp_bin, "fit", performer, "-o", tmp_path / "b.txt", "--quiet", "--budget", "0.05")
    assert small.text == (tmp_path / "b.txt").read_text()
    assert small.n_params <= 0.05 * t.positions.size
    with pytest.raises(mp.ParamError):
        mp.fit(t, budget=1.5)
    # λ from the local spread held for a time, as `mp fit --lambda-spread`;
    # the default holds it for one second.
    assert mp.fit(t, lambda_spread=1.0).text == prog.text
    spread = mp.fit(t, lambda_spread=0.25)
    run_cli(mp_bin, "fit", performer, "-o", tmp_path / "s.txt", "--quiet", "--lambda-spread", "0.25")
    assert spread.text == (tmp_path / "s.txt").read_text()
    # A shorter hold: a lower price per segment, more segments and parameters.
    assert spread.n_segments > prog.n_segments and spread.n_params > prog.n_params
    with pytest.raises(mp.ParamError, match="lambda.seconds"):
        mp.fit(t, lambda_spread=0.0)
    with pytest.raises(mp.ParamError, match="at most one"):
        mp.fit(t, lambda_spread=1.0, budget=0.1)
    # Primitive kinds and circles with an angular acceleration, as `mp fit --kinds`.
    lines = mp.fit(t, kinds=["stationary", "line"])
    run_cli(mp_bin, "fit", performer, "-o", tmp_path / "k.txt", "--quiet", "--kinds", "stationary,line")
    assert lines.text == (tmp_path / "k.txt").read_text()
    assert "circle" not in lines.text and "spline" not in lines.text
    assert lines.text != prog.text
    quad = mp.fit(t, quadratic_angle=True)
    run_cli(mp_bin, "fit", performer, "-o", tmp_path / "q.txt", "--quiet", "--quadratic-angle")
    assert quad.text == (tmp_path / "q.txt").read_text()
    with pytest.raises(mp.ParamError, match="unknown primitive kind"):
        mp.fit(t, kinds=["ellipse"])
    with pytest.raises(mp.ParamError):
        mp.fit(t, kinds=[])
    # The C0 refit under the Euclidean norm is the default; least squares, as
    # `mp fit --refit-norm squared`: the same segments, primitives moved.
    assert mp.fit(t, refit_norm="euclidean").text == prog.text
    sq = mp.fit(t, refit_norm="squared")
    run_cli(mp_bin, "fit", performer, "-o", tmp_path / "e.txt", "--quiet", "--refit-norm", "squared")
    assert sq.text == (tmp_path / "e.txt").read_text()
    assert sq.n_segments == prog.n_segments
    assert sq.text != prog.text
    with pytest.raises(mp.ParamError, match="unknown refit norm"):
        mp.fit(t, refit_norm="manhattan")


def test_counts_from_video_equal_the_cli(data, mp_bin):
    video = data("quva_repetition/videos/023_fitness.mp4")
    truth = len(np.load(data("quva_repetition/annotations/023_fitness.npy")))
    c = mp.count(str(video))
    assert abs(c.total - truth) <= 1, c
    cli = json.loads(run_cli(mp_bin, "loops", video, "--json"))
    assert c.total == cli["repetitions"]["total"]
    assert c.signal == cli["repetitions"]["signal"]


def test_run_writes_what_mp_run_writes(performer, mp_bin, tmp_path):
    s = mp.run(str(performer), tmp_path / "py", overlay_video=False)
    run_cli(mp_bin, "run", performer, "--out", tmp_path / "cli", "--quiet")
    for f in ["track.npz", "program.txt", "abstract.json", "loops.json", "report.html"]:
        assert (tmp_path / "py" / f).is_file(), f
    assert (tmp_path / "py" / "program.txt").read_text() == (tmp_path / "cli" / "program.txt").read_text()
    a = json.loads((tmp_path / "py" / "loops.json").read_text())
    b = json.loads((tmp_path / "cli" / "loops.json").read_text())
    assert a["repetitions"] == b["repetitions"]
    assert a["repetitions"]["total"] == s.counts.total
    # A loops.json reads back as the counts it holds.
    back = mp.Counts.from_json((tmp_path / "py" / "loops.json").read_text())
    assert (back.total, back.intervals, back.confidence) == (s.counts.total, s.counts.intervals, s.counts.confidence)
    # A summary pickles with everything it holds.
    s2 = pickle.loads(pickle.dumps(s))
    assert (s2.counts.total, s2.files, s2.report, s2.out_dir) == (s.counts.total, s.files, s.report, s.out_dir)
    assert s2.program == s.program and s2.stages == s.stages
    assert s2.abstract_program.text == s.abstract_program.text
    np.testing.assert_array_equal(s2.track.positions, s.track.positions)
    assert s.report is not None and s.program is not None
    assert [n for n, _, _ in s.stages][:2] == ["concrete", "abstract"]


def test_batch_writes_what_mp_batch_writes_and_resumes(performer, mp_bin, tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("a.npz", "b.npz"):
        (folder / name).write_bytes(performer.read_bytes())
    s = mp.batch(folder, tmp_path / "py", jobs=2, report=False)
    assert (s["ok"], s["failed"], s["skipped"], s["jobs"]) == (2, 0, 0, 2)
    assert s["shared_model"] is None  # tracks: no pose model to share
    assert [pathlib.Path(i["input"]).name for i in s["items"]] == ["a.npz", "b.npz"]
    run_cli(mp_bin, "batch", folder, "--out", tmp_path / "cli", "-j", 2, "--quiet")
    for item in s["items"]:
        stem = pathlib.Path(item["output"]).name
        a = json.loads((tmp_path / "py" / stem / "loops.json").read_text())
        b = json.loads((tmp_path / "cli" / stem / "loops.json").read_text())
        assert a["repetitions"] == b["repetitions"], stem
        assert item["total_repetitions"] == a["repetitions"]["total"] > 0
    # Run again: everything is complete, so everything is skipped.
    again = mp.batch(folder, tmp_path / "py", jobs=2, report=False)
    assert (again["ok"], again["skipped"]) == (0, 2)
    # A list of paths with a corrupt file: that one fails, the other runs.
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip archive")
    mixed = mp.batch([folder / "a.npz", bad], tmp_path / "mixed", report=False)
    assert (mixed["ok"], mixed["failed"]) == (1, 1)
    assert mixed["items"][1]["status"] == "failed" and "bad.npz" in mixed["items"][1]["error"]
    with pytest.raises(mp.ParamError, match="shared_model"):
        mp.batch(folder, tmp_path / "x", shared_model="sometimes")
    with pytest.raises(mp.ParamError, match="jobs"):
        mp.batch(folder, tmp_path / "y", jobs=0)


def test_extract_a_video(data, mp_bin, tmp_path):
    video = data("golfdb/golf_swing.mp4")
    t = mp.extract(str(video), max_frames=20)
    assert t.n_frames == 20 and t.skeleton == "coco17" and t.units == "px"
    assert (t.confidence > 0.5).mean() > 0.5
    # The same library call as `mp extract`: the same keypoints.
    run_cli(mp_bin, "extract", video, "--max-frames", 20, "-o", tmp_path / "k.npz", "-q")
    cli = mp.read_track(tmp_path / "k.npz")
    np.testing.assert_allclose(t.positions, cli.positions, atol=1e-6)
    np.testing.assert_allclose(t.confidence, cli.confidence, atol=1e-6)
    # The golf swing is tracked throughout: recovery changes nothing there.
    r = mp.extract(str(video), max_frames=20, recover_s=1.0)
    assert np.array_equal(r.positions, t.positions)
    with pytest.raises(mp.ParamError, match="recover_s"):
        mp.extract(str(video), max_frames=2, recover_s=-1.0)


def test_pose_on_half_the_frames(data):
    video = str(data("golfdb/golf_swing.mp4"))
    full = mp.extract(video, max_frames=21)
    half = mp.extract(video, max_frames=21, pose_fps=15)
    assert half.n_frames == 21
    # The skipped (odd) frames are filled close to the every-frame keypoints.
    both = (full.confidence[1::2] > 0) & (half.confidence[1::2] > 0)
    d = np.linalg.norm(half.positions[1::2] - full.positions[1::2], axis=-1)[both]
    assert d.size > 100 and np.median(d) < 4.0
    assert mp.extract(video, max_frames=3, pose_fps="all").n_frames == 3
    for bad in [0, -1.5, "fast"]:
        with pytest.raises(mp.ParamError, match="pose_fps"):
            mp.extract(video, max_frames=2, pose_fps=bad)
    # World coordinates on half the frames, as `mp extract --world --pose-fps`.
    world = mp.extract(video, max_frames=4, pose_fps=15, world=True)
    assert world.n_frames == 4 and world.units == "m" and world.positions.shape[2] == 3


def test_extract_reads_a_still_image_and_smooths_as_mp_extract(data):
    image = str(data("coco_sample/000000000785.jpg"))
    still = mp.extract(image)
    assert still.n_frames == 1 and still.units == "px" and still.skeleton == "coco17"
    assert (still.confidence > 0).sum() >= 10
    video = str(data("golfdb/golf_swing.mp4"))
    raw = mp.extract(video, max_frames=12)
    smooth = mp.extract(video, max_frames=12, smooth=True)
    assert smooth.n_frames == raw.n_frames == 12
    moved = np.linalg.norm(smooth.positions - raw.positions, axis=-1)
    # One-Euro smoothing changes the keypoints, by a few pixels at most.
    assert 0.0 < np.median(moved) < 10.0


def test_device_is_checked(data):
    video = str(data("golfdb/golf_swing.mp4"))
    cpu = mp.extract(video, max_frames=3, device="cpu")
    auto = mp.extract(video, max_frames=3, device="auto")
    assert np.abs(cpu.positions - auto.positions).max() < 1.0
    with pytest.raises(mp.ParamError, match="device"):
        mp.extract(video, max_frames=2, device="tpu")
    with pytest.raises(mp.ParamError, match="device"):
        mp.Analyser(device="cuda:x")


def test_bad_input_raises_clear_exceptions(tmp_path):
    with pytest.raises(mp.TrackError, match="nope.npz"):
        mp.read_track(tmp_path / "nope.npz")
    with pytest.raises(mp.MpError, match="does not exist"):
        mp.count(str(tmp_path / "missing.mp4"))
    with pytest.raises(mp.TrackError, match="T × J × D"):
        mp.Track.from_numpy(np.zeros((10, 17)), 30.0)
    with pytest.raises(mp.TrackError, match="confidence"):
        mp.Track.from_numpy(np.zeros((10, 17, 2)), 30.0, confidence=np.ones((10, 3)))
    with pytest.raises(mp.TrackError, match="fps"):
        mp.Track.from_numpy(np.zeros((10, 17, 2)), float("nan"))
    # NaN positions are missing joints; a track with no observed joint cannot be fitted.
    t = mp.Track.from_numpy(np.full((10, 3, 2), np.nan), 30.0)
    assert (t.confidence == 0).all()
    with pytest.raises(mp.ProgramError):
        mp.fit(t)
    with pytest.raises(mp.ParamError):
        mp.extract(str(tmp_path / "x.mp4"), model="nonexistent")
    bad = tmp_path / "corrupt.mp4"
    bad.write_bytes(b"\x00\x00\x00\x18ftypmp42 junk")
    with pytest.raises(mp.PoseError, match="corrupt.mp4"):
        mp.extract(str(bad))
    with pytest.raises(mp.TrackError):
        mp.Track.from_bytes(b"garbage")


def test_the_gil_is_released_while_rust_works(performer):
    t = mp.read_track(performer)
    ticks = 0
    done = threading.Event()

    def work():
        mp.fit(t)
        done.set()

    th = threading.Thread(target=work)
    th.start()
    t0 = time.perf_counter()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    elapsed = time.perf_counter() - t0
    th.join()
    # While fit ran (hundreds of milliseconds), this thread kept running.
    assert elapsed > 0.05
    assert ticks > 10, f"only {ticks} ticks in {elapsed:.3f} s: the GIL was held"


def test_the_plot_example(data, tmp_path):
    import importlib.util
    import pathlib

    root = pathlib.Path(__file__).resolve().parents[3]
    spec = importlib.util.spec_from_file_location("plot_repetitions", root / "examples" / "plot_repetitions.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = tmp_path / "reps.png"
    c = mod.plot(str(data("quva_repetition/videos/023_fitness.mp4")), str(out))
    assert out.stat().st_size > 10_000
    assert c.total == 7


def test_predict_equals_the_cli(performer, mp_bin, tmp_path):
    t = mp.read_track(performer)
    pred, why = mp.predict(t, 30, observe=120)
    assert pred.n_frames == 30 and pred.joint_names == t.joint_names
    run_cli(mp_bin, "predict", performer, "--observe", 120, "--horizon", 30, "-o", tmp_path / "p.npz")
    np.testing.assert_allclose(pred.positions, mp.read_track(tmp_path / "p.npz").positions, atol=1e-9)
    const, _ = mp.predict(t, 5, method="constant", observe=50)
    np.testing.assert_allclose(const.positions[-1], t.positions[49])
    with pytest.raises(mp.ForecastError, match="observe"):
        mp.predict(t, 5, observe=0)
    with pytest.raises(mp.ParamError):
        mp.predict(t, 5, method="crystal-ball")
    with pytest.raises(mp.ForecastError):
        mp.predict(t, 10**12)


def test_refine_a_3d_track(data, mp_bin, tmp_path):
    video = data("golfdb/golf_swing.mp4")
    run_cli(mp_bin, "extract", video, "--world", "--max-frames", 60, "-o", tmp_path / "w.npz", "-q")
    w = mp.read_track(tmp_path / "w.npz")
    # Python's world landmarks are the command's.
    wp = mp.extract(video, max_frames=60, world=True)
    assert wp.dims == 3 and wp.n_joints == 33 and wp.units == "m"
    np.testing.assert_allclose(wp.positions, w.positions, atol=1e-6)
    r = mp.refine(w)
    assert r.joint_names == w.joint_names and r.n_frames == w.n_frames
    assert np.isfinite(r.positions).all()
    run_cli(mp_bin, "refine", tmp_path / "w.npz", "-o", tmp_path / "r.npz")
    np.testing.assert_allclose(r.positions, mp.read_track(tmp_path / "r.npz").positions, atol=1e-6)
    with pytest.raises(mp.RefineError):
        # A 2D track cannot be refined: the networks read 3D motion.
        mp.refine(mp.Track.from_numpy(np.zeros((60, 17, 2)), 30.0, skeleton="coco17"))


def test_grammar_symbols_and_learn_equal_the_cli(performer, mp_bin, tmp_path):
    t = mp.read_track(performer).slice(0, 330)
    t.save(tmp_path / "part.npz")
    s = mp.grammar_symbols(t, k=4)
    run_cli(mp_bin, "grammar", "symbols", tmp_path / "part.npz", "--k", 4, "-o", tmp_path / "s.json")
    cli = json.loads((tmp_path / "s.json").read_text())
    assert s["text"] == cli["text"] and len(s["text"].split()) > 4
    g = mp.grammar_learn(s)
    run_cli(mp_bin, "grammar", "learn", tmp_path / "s.json", "-o", tmp_path / "g.json")
    gc = json.loads((tmp_path / "g.json").read_text())
    assert g["grammar"] == gc["grammar"]
    assert g["sentences"] == gc["sentences"]
    with pytest.raises(mp.GrammarError):
        mp.grammar_learn({"not": "symbols"})


def test_frame_rate_travels_with_the_file(performer, tmp_path):
    t = mp.read_track(performer)
    fast = mp.Track.from_numpy(t.positions, 60.0, confidence=t.confidence, skeleton="coco17")
    fast.save(tmp_path / "t60.csv")
    assert mp.read_track(tmp_path / "t60.csv").fps == 60.0  # the CSV's time column
    np.save(tmp_path / "t.npy", t.positions)
    with pytest.warns(UserWarning, match="30 fps assumed"):
        assert mp.read_track(tmp_path / "t.npy").fps == 30.0
    assert mp.read_track(tmp_path / "t.npy", fps=60).fps == 60.0
    assert mp.read_track(tmp_path / "t60.csv", fps=25).fps == 25.0


def test_results_pickle_and_arrays_are_read_only(performer):
    t = mp.read_track(performer)
    with pytest.raises(ValueError, match="read-only"):
        t.positions[:, :, 0] += 100
    with pytest.raises(ValueError, match="read-only"):
        t.confidence[0, 0] = 0.5
    edited = t.positions.copy()
    edited[:, :, 0] += 100
    moved = mp.Track.from_numpy(edited, t.fps, confidence=t.confidence, skeleton="coco17")
    np.testing.assert_allclose(moved.positions[:, :, 0], t.positions[:, :, 0] + 100)
    prog = mp.fit(t)
    back = pickle.loads(pickle.dumps(prog))
    assert back == prog and back.text == prog.text
    counts = mp.count(t)
    c2 = pickle.loads(pickle.dumps(counts))
    assert (c2.total, c2.signal, c2.method, c2.confidence, c2.intervals) == (
        counts.total, counts.signal, counts.method, counts.confidence, counts.intervals)
    ab = mp.abstract(t)
    ab2 = pickle.loads(pickle.dumps(ab))
    assert ab2.text == ab.text and ab2.program_loops == ab.program_loops and ab2.concrete == prog
    with pytest.raises(mp.MpError, match="summary"):
        mp.Summary.from_bytes(b"not a summary")
    with pytest.raises(mp.ParamError, match="version"):
        mp.Counts.from_json('{"version": 1, "total_repetitions": 3}')
    # Through a process pool, as a data-science workflow would.
    import multiprocessing as mpc
    import operator
    with mpc.get_context("spawn").Pool(1) as pool:
        got = pool.map(operator.attrgetter("total"), [counts])
        texts = pool.map(operator.attrgetter("text"), [prog])
    assert got == [counts.total] and texts == [prog.text]


def test_functions_take_a_track_a_path_or_an_array(performer, tmp_path):
    t = mp.read_track(performer)
    by_track = mp.fit(t)
    assert mp.fit(performer) == by_track
    assert mp.fit(str(performer)) == by_track
    with pytest.warns(UserWarning, match="30 fps assumed"):
        from_array = mp.fit(t.positions)
    assert from_array.n_frames == by_track.n_frames
    with pytest.warns(UserWarning, match="30 fps assumed"):
        assert mp.count(t.positions).total == mp.count(t).total
    assert mp.predict(performer, 5, method="constant")[0].n_frames == 5
    with pytest.raises(mp.ParamError, match="extract"):
        mp.fit(tmp_path / "clip.mp4")
    with pytest.raises(mp.ParamError, match="takes a Track"):
        mp.fit({"not": "a track"})


def test_params_dict_sets_every_setting_as_mp_params(performer, mp_bin, tmp_path):
    d = mp.default_params()
    assert d == json.loads(run_cli(mp_bin, "params"))
    assert d["pose"]["model"] == "full" and d["output"]["report"] is True
    # A partial dict: the report is off, everything else keeps its default.
    s = mp.run(performer, tmp_path / "a", params={"output": {"report": False}})
    assert (tmp_path / "a" / "loops.json").is_file()
    assert not (tmp_path / "a" / "report.html").exists()
    # Keywords apply on top of the dict.
    mp.run(performer, tmp_path / "b", params={"output": {"report": False}}, report=True)
    assert (tmp_path / "b" / "report.html").is_file()
    whole = mp.run(performer, tmp_path / "c", params=d, report=False)
    assert whole.counts.total == s.counts.total
    with pytest.raises(mp.ParamError, match="reprot"):
        mp.run(performer, tmp_path / "d", params={"output": {"reprot": False}})
    # A value out of range is refused by its library's check, naming the field.
    with pytest.raises(mp.MpError, match="min_strength"):
        mp.Analyser(params={"count": {"min_strength": -1.0}})
