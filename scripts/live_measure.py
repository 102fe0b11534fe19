#!/usr/bin/env python3
"""Streams QUVA videos at their own speed into `mp live - --json` and compares
its final count with `mp loops`, and each labelled cycle end with the wall-clock
time of the `rep` line that brings the count to it. The delay is split in two:
how far the analysis was behind the stream when it wrote the line (wall-clock
time since the sender started less the line's stream time `t`), and the
counter's own wait (`t` less the labelled end).

    python3 scripts/live_measure.py [--mp target/release/mp] [--encode] NAME...

The video is encoded once into MPEG-TS (libx264, zerolatency) and sent at its
own speed without encoding again (`ffmpeg -re -i V.ts -c copy -f mpegts
pipe:1`), as a camera's stream arrives encoded; with `--encode` the sender
encodes while it sends (`ffmpeg -re -i V.mp4 -c:v libx264 -tune zerolatency
-f mpegts pipe:1`), which takes CPU from the analysis on the same machine.

NAME is a video of quva_repetition/videos without `.mp4` (e.g. 023_fitness);
the data folder is MP_DATA_DIR, else ../shared/data. Prints one Markdown table
row per video (docs/results/live.md, "Live analysis").
"""
import argparse, ast, json, os, struct, subprocess, sys, tempfile, time


def npy_ints(path):
    d = open(path, "rb").read()
    n = struct.unpack("<H", d[8:10])[0]
    h = ast.literal_eval(d[10:10 + n].decode())
    k = h["shape"][0]
    return list(struct.unpack("<%dq" % k, d[10 + n:10 + n + 8 * k]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mp", default="target/debug/mp")
    ap.add_argument("--encode", action="store_true")
    ap.add_argument("--pose-fps", default=None, help="passed to mp live (default: mp live's)")
    ap.add_argument("names", nargs="+")
    a = ap.parse_args()
    data = os.environ.get("MP_DATA_DIR", "../shared/data") + "/quva_repetition"
    pooled, bound = [], []
    print("| video | labelled | `mp loops` | `mp live` | analysed | dropped | median delay (s) | largest delay (s) "
          "| behind the stream (s) | counter's wait (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in a.names:
        v = f"{data}/videos/{name}.mp4"
        labels = npy_ints(f"{data}/annotations/{name}.npy")
        rate = subprocess.check_output(["ffprobe", "-v", "error", "-select_streams", "v:0",
                                        "-show_entries", "stream=avg_frame_rate", "-of", "csv=p=0", v])
        num, den = rate.decode().strip().split("/")
        fps = float(num) / float(den)
        loops = json.loads(subprocess.check_output([a.mp, "loops", v, "--json"]))["repetitions"]["total"]
        encode = ["-an", "-c:v", "libx264", "-tune", "zerolatency", "-f", "mpegts"]
        if a.encode:
            sender = ["-re", "-i", v] + encode + ["pipe:1"]
        else:
            ts = os.path.join(tempfile.mkdtemp(), "v.ts")
            subprocess.run(["ffmpeg", "-v", "error", "-nostdin", "-i", v] + encode + [ts], check=True)
            sender = ["-re", "-i", ts, "-c", "copy", "-f", "mpegts", "pipe:1"]
        t0 = time.time()
        ff = subprocess.Popen(["ffmpeg", "-v", "error", "-nostdin"] + sender, stdout=subprocess.PIPE)
        live = [a.mp, "live", "-", "--json"] + (["--pose-fps", a.pose_fps] if a.pose_fps else [])
        mp = subprocess.Popen(live, stdin=ff.stdout, stdout=subprocess.PIPE)
        ff.stdout.close()
        events = [(time.time() - t0, json.loads(line)) for line in mp.stdout]
        mp.wait()
        ff.wait()
        summary = events[-1][1]
        totals = {p["id"]: p["total_repetitions"] for p in summary["people"]}
        # The stream's count: the person counted most; the scene (person 0)
        # when no person's repetitions were counted.
        people = {k: v for k, v in totals.items() if k != 0}
        main_id = max(people, key=people.get) if people else None
        if main_id is None or people[main_id] == 0:
            main_id = 0 if totals.get(0) else main_id
        reps = [(w, e["t"]) for w, e in events if e["type"] == "rep" and e["person"] == main_id]
        median = lambda v: sorted(v)[len(v) // 2] if v else float("nan")
        delays = sorted(w - end / fps for (w, _), end in zip(reps, labels))
        behind = [w - t for (w, t), _ in zip(reps, labels)]
        wait = [t - end / fps for (_, t), end in zip(reps, labels)]
        top = delays[-1] if delays else float("nan")
        pooled.extend(delays)
        # The least delay of a counter that must see the motion repeat: the
        # first repetition reached at the end of the second, the others at their end.
        ends = [end / fps for end in labels]
        bound.extend([ends[1] - ends[0]] + [0.0] * (len(ends) - 1) if len(ends) > 1 else [])
        print(f"| {name} | {len(labels)} | {loops} | {totals.get(main_id, 0)} | {summary['frames']} "
              f"| {summary['dropped']} | {median(delays):.2f} | {top:.2f} | {median(behind):.2f} "
              f"| {median(wait):.2f} |")
        sys.stdout.flush()
    q = lambda v, f: sorted(v)[min(len(v) - 1, int(f * len(v)))] if v else float("nan")
    print(f"\nall {len(pooled)} repetitions: median delay {q(pooled, 0.5):.2f} s, 90th percentile "
          f"{q(pooled, 0.9):.2f} s; a counter that must see the motion repeat: median "
          f"{q(bound, 0.5):.2f} s, 90th percentile {q(bound, 0.9):.2f} s ({len(bound)} repetitions)")


if __name__ == "__main__":
    main()
