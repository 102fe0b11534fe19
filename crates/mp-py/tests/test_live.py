"""`motion_programs.live`: the events of `mp live --json` as dicts, on shared QUVA videos; leaving
the loop early or Ctrl-C stops the run and its FFmpeg decoder; other Python threads run while it
waits; a missing file raises PoseError naming it."""

import json
import os
import signal
import subprocess
import sys
import threading
import time

import pytest

import motion_programs as mp

SHORT = "quva_repetition/videos/023_fitness.mp4"  # 4.3 s, 7 labelled repetitions
LONGER = "quva_repetition/videos/000_rope_beach.mp4"  # 7.9 s, 17 labelled repetitions


def ffmpeg_children():
    """Process ids of the `ffmpeg` processes whose parent is this Python process."""
    out = subprocess.run(["ps", "-o", "pid=,ppid=,comm=", "-e"], capture_output=True, text=True, check=True)
    me = os.getpid()
    found = []
    for line in out.stdout.splitlines():
        parts = line.split(None, 2)
        if len(parts) == 3 and int(parts[1]) == me and parts[2].strip().startswith("ffmpeg"):
            found.append(int(parts[0]))
    return found


def totals(summary):
    return {p["id"]: p["total_repetitions"] for p in summary["people"]}


def test_events_of_a_file_match_the_command_line(data, mp_bin):
    video = data(SHORT)
    events = list(mp.live(video))
    assert events, "no event"
    assert events[-1]["type"] == "summary"
    assert all(e["type"] != "summary" for e in events[:-1])
    assert all(e["type"] != "error" for e in events)
    counts = {}
    entered = set()
    for e in events:
        if e["type"] == "enter":
            entered.add(e["person"])
        if e["type"] == "rep":
            assert e["person"] in entered, e
            assert e["count"] == counts.get(e["person"], 0) + 1, e
            assert e["end"] > e["start"], e
            counts[e["person"]] = e["count"]
    summary = events[-1]
    assert summary["frames"] > 100  # 4.3 s at 30 fps, every frame analysed
    assert summary["dropped"] == 0
    assert totals(summary) == {p: counts.get(p, 0) for p in entered}
    assert max(totals(summary).values()) >= 5

    out = subprocess.run([str(mp_bin), "live", str(video), "--json"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    lines = [json.loads(line) for line in out.stdout.splitlines()]
    cli = lines[-1]
    assert cli["type"] == "summary"
    assert totals(cli) == totals(summary)
    assert cli["frames"] == summary["frames"]
    # The same events, in the same order, with the same keys (the status lines' speeds differ).
    assert [(e["type"], sorted(e)) for e in lines] == [(e["type"], sorted(e)) for e in events]
    reps = lambda evs: [(e["person"], e["count"], e["start"], e["end"]) for e in evs if e["type"] == "rep"]
    assert reps(lines) == reps(events)


def test_breaking_the_loop_stops_the_run_and_its_decoder(data):
    video = data(LONGER)
    seen = None
    it = mp.live(video)
    for e in it:
        if e["type"] == "rep":
            seen = e
            assert ffmpeg_children(), "the decoder should still be running"
            break
    assert seen is not None, "no repetition reported"
    started = time.monotonic()
    del it  # what leaving a `for` loop over `mp.live(...)` does to its iterator
    stopped = time.monotonic() - started
    left = ffmpeg_children()
    assert not left, f"ffmpeg still running: {left}"
    print(f"stopped {stopped:.2f} s after the loop was left")
    # A new run works right after.
    with mp.live(video, duration=1.0) as events:
        again = list(events)
    assert again[-1]["type"] == "summary"
    assert 20 <= again[-1]["frames"] <= 31  # 1 s of stream time at 29.97 fps
    assert not ffmpeg_children()


def test_close_ends_the_iteration(data):
    it = mp.live(data(SHORT))
    first = next(it)
    assert first["type"] in ("enter", "status", "rep")
    it.close()
    assert not ffmpeg_children()
    with pytest.raises(StopIteration):
        next(it)


def test_other_threads_run_while_the_loop_waits(data):
    video = data(SHORT)
    ticks = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks[0] += 1
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    try:
        during = []
        for e in mp.live(video, realtime=True):
            during.append(ticks[0])
    finally:
        stop.set()
        t.join()
    assert e["type"] == "summary"
    # The realtime run takes the video's 4.3 s; the thread ticks about a thousand times a second
    # when it gets the interpreter, and would not tick at all if the loop held the GIL while waiting.
    assert during[-1] - during[0] > 500, during


def test_a_missing_file_raises_pose_error_naming_it(tmp_path):
    missing = tmp_path / "no_such_video.mp4"
    events = []
    with pytest.raises(mp.PoseError, match="no_such_video.mp4"):
        for e in mp.live(missing):
            events.append(e)
    assert [e["type"] for e in events] == ["error", "summary"]
    assert events[0]["message"]
    assert events[1]["frames"] == 0


def test_an_option_out_of_range_raises_param_error(data):
    with pytest.raises(mp.ParamError, match="window"):
        mp.live(data(SHORT), window=-1.0)


CHILD = """
import os, signal, subprocess, sys
import motion_programs as mp
signal.signal(signal.SIGINT, signal.default_int_handler)
try:
    for e in mp.live(sys.argv[1], realtime=True):
        print(e["type"], flush=True)
    print("ended", flush=True)
except KeyboardInterrupt:
    ps = subprocess.run(["ps", "-o", "ppid=,comm=", "-e"], capture_output=True, text=True).stdout
    left = [l for l in ps.splitlines() if l.split()[0] == str(os.getpid()) and "ffmpeg" in l]
    print("interrupted", len(left), flush=True)
"""


def test_ctrl_c_stops_the_run(data):
    video = data("quva_repetition/videos/013_weights_floor.mp4")  # 26 s at its own speed
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(video)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    first = child.stdout.readline()  # the run is under way
    assert first.strip() in ("enter", "status", "rep"), first + child.stderr.read()
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=60)
    assert child.returncode == 0, err
    assert out.splitlines()[-1] == "interrupted 0", out + err


def test_out_writes_the_files_of_a_run(data, tmp_path):
    video = data(SHORT)
    out = tmp_path / "live"
    events = list(mp.live(video, duration=2.0, out=out, pose_fps="auto"))
    summary = events[-1]
    assert summary["type"] == "summary"
    assert summary["out"] == str(out)
    # Every second frame of a 29-fps video goes through the pose model.
    assert summary["posed"] == (summary["frames"] + 1) // 2
    for name in ["track.npz", "program.txt", "loops.json", "report.html"]:
        assert (out / name).is_file(), name
    assert not [p for p in out.iterdir() if "spool" in p.name]
    track = mp.read_track(out / "track.npz")
    assert track.n_frames == summary["frames"]
    with pytest.raises(mp.ParamError, match="pose_fps"):
        mp.live(video, pose_fps=-1)
    with open(out / "loops.json") as f:
        assert json.load(f)["repetitions"]["total"] >= 0
