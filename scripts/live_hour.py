#!/usr/bin/env python3
"""An hour-long stream at 30 fps with one person, into `mp live - --json`:
frames dropped, and the mp process's memory at 10, 30 and 60 minutes.

    python3 scripts/live_hour.py [--mp target/release/mp] [--minutes 60] [VIDEO]

VIDEO (default: the QUVA video 023_fitness of the data folder, MP_DATA_DIR
or ../shared/data) is encoded once at 30 fps into MPEG-TS, then looped and
sent at its own speed without encoding again (`ffmpeg -re -stream_loop -1
-i clip.ts -c copy -f mpegts pipe:1`), so that the sender takes almost no
CPU from the analysis. Prints a Markdown table
(docs/results/live.md, "Live analysis"): minute, frames analysed and dropped so
far, resident memory now and at its peak.
"""
import argparse, json, os, subprocess, sys, tempfile, threading, time


def rss(pid):
    now = peak = 0
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    now = int(line.split()[1]) // 1024
                elif line.startswith("VmHWM:"):
                    peak = int(line.split()[1]) // 1024
    except OSError:
        pass
    return now, peak


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mp", default="target/release/mp")
    ap.add_argument("--minutes", type=float, default=60)
    ap.add_argument("video", nargs="?")
    a = ap.parse_args()
    data = os.environ.get("MP_DATA_DIR", "../shared/data")
    video = a.video or f"{data}/quva_repetition/videos/023_fitness.mp4"
    seconds = a.minutes * 60
    clip = os.path.join(tempfile.mkdtemp(), "clip.ts")
    subprocess.run(["ffmpeg", "-v", "error", "-nostdin", "-i", video, "-an", "-vf", "fps=30", "-c:v", "libx264",
                    "-tune", "zerolatency", "-f", "mpegts", clip], check=True)
    ff = subprocess.Popen(["ffmpeg", "-v", "error", "-nostdin", "-re", "-stream_loop", "-1", "-i", clip,
                           "-t", str(seconds), "-c", "copy", "-f", "mpegts", "pipe:1"], stdout=subprocess.PIPE)
    mp = subprocess.Popen([a.mp, "live", "-", "--json"], stdin=ff.stdout, stdout=subprocess.PIPE, text=True)
    ff.stdout.close()
    last = {}

    def read():
        for line in mp.stdout:
            e = json.loads(line)
            if e["type"] in ("status", "summary"):
                last.update(e)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    t0 = time.time()
    marks = [m for m in (1, 10, 30, 60, 120, 240) if m <= a.minutes]
    print("| minute | frames analysed | dropped | dropped % | resident MB | peak resident MB |")
    print("|---|---|---|---|---|---|")
    for m in marks:
        while time.time() - t0 < m * 60 - 5 and mp.poll() is None:
            time.sleep(1)
        now, peak = rss(mp.pid)
        f, d = last.get("frames", 0), last.get("dropped", 0)
        print(f"| {m} | {f} | {d} | {100 * d / max(f + d, 1):.2f} | {now} | {peak} |")
        sys.stdout.flush()
    mp.wait()
    ff.wait()
    reader.join()
    f, d = last.get("frames", 0), last.get("dropped", 0)
    print(f"| end | {f} | {d} | {100 * d / max(f + d, 1):.2f} | | |")


if __name__ == "__main__":
    main()
