"""Several people in one video: two QUVA performers side by side (a two-panel video made with
FFmpeg) are tracked as two people with steady ids, one in each half of the frame, by
extract(people=True), count(), an Analyser and `mp loops` alike."""

import json
import pickle
import shutil
import subprocess

import numpy as np
import pytest

import motion_programs as mp

LEFT = "quva_repetition/videos/020_fitness.mp4"
RIGHT = "quva_repetition/videos/027_fitness.mp4"
ANNOTATIONS = "quva_repetition/annotations/{}.npy"
SECONDS = 5
FPS = 30
PANEL_W, PANEL_H = 640, 360

# The two-panel video and its people, made once per session (each pose pass takes seconds).
_made = {}


def run_cli(mp_bin, *args):
    out = subprocess.run([str(mp_bin), *map(str, args)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out.stdout


@pytest.fixture
def two_panel(data, skip_needs, tmp_path_factory):
    """A 5-second video, 1280 × 360 at 30 fps: 020_fitness (one performer) on the left half and
    027_fitness (another) on the right."""
    left, right = data(LEFT), data(RIGHT)
    ffmpeg = shutil.which("ffmpeg")
    if ffmpeg is None:
        skip_needs("ffmpeg", "ffmpeg is not installed")
    if "video" not in _made:
        out = tmp_path_factory.mktemp("people") / "two_panel.mp4"
        scale = f"fps={FPS},scale={PANEL_W}:{PANEL_H},setsar=1"
        graph = f"[0:v]{scale}[a];[1:v]{scale}[b];[a][b]hstack=inputs=2[v]"
        base = [ffmpeg, "-v", "error", "-y", "-i", str(left), "-i", str(right),
                "-filter_complex", graph, "-map", "[v]", "-t", str(SECONDS), "-an", "-pix_fmt", "yuv420p"]
        r = subprocess.run(base + ["-c:v", "libx264", "-preset", "ultrafast", "-crf", "18", str(out)],
                           capture_output=True, text=True)
        if r.returncode != 0:  # An FFmpeg without x264.
            r = subprocess.run(base + ["-c:v", "mpeg4", "-q:v", "2", str(out)], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        _made["video"] = out
    return _made["video"]


@pytest.fixture
def two_people(two_panel):
    """The people of the two-panel video, from extract(people=True)."""
    if "people" not in _made:
        _made["people"] = mp.extract(str(two_panel), people=True)
    return _made["people"]


@pytest.fixture
def two_counts(two_panel):
    """count() of the two-panel video."""
    if "counts" not in _made:
        _made["counts"] = mp.count(str(two_panel))
    return _made["counts"]


def truth(data, rel):
    """Repetitions of a QUVA video ending within the first SECONDS of it (its annotations are
    the frames where each repetition ends, at the video's own rate)."""
    ends = np.load(data(ANNOTATIONS.format(rel.split("/")[-1][:-4])))
    fps = float(subprocess.run(
        ["ffprobe", "-v", "error", "-select_streams", "v:0", "-show_entries", "stream=r_frame_rate",
         "-of", "csv=p=0", str(data(rel))], capture_output=True, text=True, check=True,
    ).stdout.strip().split("/")[0])
    return int((ends < SECONDS * fps).sum())


def centre_x(person):
    x0, _, x1, _ = person.box
    return (x0 + x1) / 2


def test_extract_finds_one_person_per_panel(two_people):
    people = two_people
    assert isinstance(people, mp.People)
    assert len(people) == 2 and people.ids == [1, 2], people
    assert people.n_frames == SECONDS * FPS and people.fps == FPS
    assert [p.id for p in people] == [1, 2]
    left, right = sorted(people, key=centre_x)
    # One performer in each half: their mean boxes lie in their own panel.
    assert centre_x(left) < PANEL_W < centre_x(right), (left.box, right.box)
    assert left.box[2] <= PANEL_W <= right.box[0], (left.box, right.box)
    for p in people:
        assert p.frames_found >= 0.8 * people.n_frames, p
        assert 0 <= p.first_frame <= p.last_frame < people.n_frames
        t = p.track
        assert t.n_frames == p.last_frame - p.first_frame + 1
        assert t.skeleton == "coco17" and t.units == "px" and t.fps == people.fps
        found = (t.confidence > 0).any(axis=1)
        assert found.sum() == p.frames_found
        # The whole-video track: the person's own frames in place, nobody outside them.
        full = people.track(p.id)
        assert full.n_frames == people.n_frames
        span = slice(p.first_frame, p.last_frame + 1)
        np.testing.assert_array_equal(full.positions[span], t.positions)
        np.testing.assert_array_equal(full.confidence[span], t.confidence)
        assert (full.confidence[: p.first_frame] == 0).all()
        assert (full.confidence[p.last_frame + 1 :] == 0).all()
        # Their joints stay in their own half on the frames where they were found.
        xs = t.positions[..., 0][t.confidence > 0]
        assert ((xs < PANEL_W) if p.id == left.id else (xs > PANEL_W)).mean() > 0.95, p
        # Boxes per video frame: None outside the span and where the person was not found.
        first_found = p.first_frame + int(np.argmax(found))
        x0, y0, x1, y1 = p.box_at(first_found)
        assert x0 <= x1 and y0 <= y1
        assert p.box_at(p.last_frame + 1) is None
        if p.first_frame > 0:
            assert p.box_at(p.first_frame - 1) is None
    # Lookups by id.
    assert people.main in (1, 2)
    np.testing.assert_array_equal(people.main_track().positions, people.track(people.main).positions)
    assert people[2] == people.get(2) and people[2].id == 2
    assert 1 in people and 3 not in people and "1" not in people
    assert people.get(3) is None and people.get(3, "none") == "none"
    with pytest.raises(KeyError, match="no person 3"):
        people[3]
    with pytest.raises(KeyError):
        people.track(0)


def test_people_pickle_and_files(two_people, tmp_path):
    people = two_people
    back = pickle.loads(pickle.dumps(people))
    assert isinstance(back, mp.People) and back == people
    assert back.ids == people.ids and back.main == people.main
    for a, b in zip(back, people):
        assert a == b and a.box == b.box
        np.testing.assert_array_equal(a.track.positions, b.track.positions)
    assert mp.People.from_bytes(people.to_bytes()) == people
    # One person pickles on its own too.
    one = people[people.main]
    assert pickle.loads(pickle.dumps(one)) == one
    with pytest.raises(mp.TrackError):
        mp.People.from_bytes(b"garbage")
    # The file forms: npz with a person axis, JSON, the binary form.
    for ext in ["npz", "json", "mpt"]:
        f = tmp_path / f"people.{ext}"
        people.save(f)
        r = mp.read_people(f)
        assert r.ids == people.ids and r.n_frames == people.n_frames and r.fps == people.fps, ext
        assert r.main == people.main, ext
        for a, b in zip(r, people):
            assert (a.first_frame, a.last_frame, a.frames_found) == (b.first_frame, b.last_frame, b.frames_found)
            np.testing.assert_allclose(a.track.positions, b.track.positions, atol=1e-9, err_msg=ext)
            np.testing.assert_allclose(a.track.confidence, b.track.confidence, atol=1e-9, err_msg=ext)
        # A people file read as one track gives the main person's.
        np.testing.assert_allclose(mp.read_track(f).positions, people.main_track().positions, atol=1e-9)
    with pytest.raises(mp.TrackError):
        people.save(tmp_path / "people.csv")
    # Any track file reads as one person over the whole track.
    people.main_track().save(tmp_path / "one.npz")
    one = mp.read_people(tmp_path / "one.npz")
    assert one.ids == [1] and one.main == 1 and len(one[1].track) == people.n_frames


def test_count_gives_every_person(data, two_counts, two_people):
    c = two_counts
    people = c.people
    assert [p["id"] for p in people] == [1, 2], people
    assert [p["main"] for p in people].count(True) == 1
    main = next(p for p in people if p["main"])
    assert c.person == main["id"] == two_people.main
    assert c.total == main["repetitions"]["total"]
    assert c.intervals == main["repetitions"]["intervals"]
    by_panel = {}
    for p, q in zip(people, two_people):
        # The tracker of extract(people=True) and of count() is the same.
        assert (p["first_frame"], p["last_frame"], p["frames_found"]) == (q.first_frame, q.last_frame, q.frames_found)
        assert p["box"] == list(q.box)
        # Both were seen for the whole clip: both analysed, each from their own frames.
        assert p["analysed"], p
        r = p["repetitions"]
        assert r["signal"] in ("keypoints", "frames") and r["method"] in ("period", "intervals", "none")
        assert 0 <= r["confidence"] <= 1
        assert sum(i["count"] for i in r["intervals"]) == r["total"]
        by_panel[LEFT if centre_x(q) < PANEL_W else RIGHT] = r["total"]
    # Each performer's repetitions are counted from their own motion.
    for rel, n in by_panel.items():
        assert abs(n - truth(data, rel)) <= 1, (rel, n, truth(data, rel), people)


def test_people_equal_the_cli(mp_bin, two_panel, two_counts):
    c = two_counts
    cli = json.loads(run_cli(mp_bin, "loops", two_panel, "--json"))
    assert cli["person"] == c.person and cli["repetitions"]["total"] == c.total
    assert len(cli["people"]) == len(c.people) == 2
    # The same entries.
    assert c.people == cli["people"]


def test_person_choice_on_a_video(two_panel, two_people):
    # Only person 1, whose results are then the top-level ones.
    a = mp.Analyser(person=1, report=False, overlay_video=False)
    s = a.analyse(str(two_panel))
    assert s.person == 1 and s.counts.person == 1
    entries = {p["id"]: p for p in s.people}
    assert sorted(entries) == [1, 2] and entries[1]["main"] and not entries[2]["main"]
    assert entries[1]["analysed"] and not entries[2]["analysed"]
    assert entries[2]["repetitions"] is None
    assert s.counts.total == entries[1]["repetitions"]["total"]
    assert s.tracked == two_people
    np.testing.assert_array_equal(s.track.positions, two_people.track(1).positions)
    assert s.program_of(1) is not None and s.program_of(1) == s.program
    assert s.program_of(2) is None and s.abstract_program_of(2) is None
    # A person who is not in the video.
    with pytest.raises(mp.ParamError, match="no person 9"):
        mp.Analyser(person=9, max_frames=30, report=False, overlay_video=False).analyse(str(two_panel))


def test_person_options_are_checked(performer, tmp_path):
    t = mp.read_track(performer)
    # A track has no people; the options are still checked.
    c = mp.count(t, person="main")
    assert c.people == [] and c.person is None
    for bad in ["nobody", 0, -1, True, 1.5]:
        with pytest.raises(mp.ParamError, match="person"):
            mp.count(t, person=bad)
    with pytest.raises(mp.ParamError, match="max_people"):
        mp.count(t, max_people=0)
    with pytest.raises(mp.ParamError, match="person"):
        mp.run(t, tmp_path / "out", person="everyone")
    with pytest.raises(mp.ParamError, match="person"):
        mp.Analyser(person="x")
    # people=True needs the people tracker.
    with pytest.raises(mp.ParamError, match="people=True"):
        mp.extract(str(tmp_path / "x.mp4"), people=True, single_person=True)
    with pytest.raises(mp.ParamError, match="people=True"):
        mp.extract(str(tmp_path / "x.mp4"), people=True, model="movenet")


def test_the_guide_example_runs(data, two_panel, tmp_path):
    """docs/PYTHON.md's example, on real videos: a QUVA clip for `squats.mp4` and the two-panel
    video for `gym.mp4`; every line runs, and what its comments say holds."""
    import pathlib
    import re
    guide = (pathlib.Path(__file__).resolve().parents[3] / "docs/PYTHON.md").read_text()
    code = re.search(r"## Example\n\n```python\n(.*?)```", guide, re.S).group(1)
    code = (code.replace('"squats.mp4"', repr(str(data("quva_repetition/videos/023_fitness.mp4"))))
                .replace('"gym.mp4"', repr(str(two_panel)))
                .replace('"out/"', repr(str(tmp_path / "out"))))
    scope = {}
    exec(compile(code, "docs/PYTHON.md", "exec"), scope)
    assert scope["track"].positions.shape[1:] == (17, 2)
    assert scope["counts"].total == scope["summary"].counts.total == 7
    assert scope["people"].ids == [1, 2]
    assert (tmp_path / "out" / "report.html").is_file()
