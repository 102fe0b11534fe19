#!/usr/bin/env python3
"""BlazePose side by side: `mp extract --single-person` against MediaPipe's
own `Pose.process()` (mediapipe 0.10.21, model_complexity=1), on the same
videos in one run, alternating video by video.

Both are timed without decoding: MediaPipe on frames decoded beforehand
(PyAV), `mp` by its own per-frame estimator time (`mp extract` reports the
frames per second of its median frame); MediaPipe's figure is the same
statistic, 1000 / median ms. The keypoints are compared in pixels on the
frames where both found a pose: all 33 landmarks, and the landmarks
MediaPipe itself calls visible (visibility > 0.5, as `cargo xtask eval pose`
counts them; an occluded landmark's place is a guess in both pipelines).

    python3 -m venv .cache/venv-mediapipe
    .cache/venv-mediapipe/bin/pip install mediapipe==0.10.21 av
    .cache/venv-mediapipe/bin/python scripts/pose_speed.py --mp target/release/mp \\
        ../shared/data/quva_repetition/videos/*.mp4
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

import av
import numpy as np


def mediapipe_run(path):
    import mediapipe as mediapipe

    t0 = time.perf_counter()
    frames = [f.to_ndarray(format="rgb24") for f in av.open(path).decode(video=0)]
    decode_s = time.perf_counter() - t0
    h, w = frames[0].shape[:2]
    pose = mediapipe.solutions.pose.Pose(
        static_image_mode=False, model_complexity=1, smooth_landmarks=False
    )
    ms, kps = [], []
    for f in frames:
        t = time.perf_counter()
        r = pose.process(f)
        ms.append(1000 * (time.perf_counter() - t))
        if r.pose_landmarks:
            kps.append([[p.x * w, p.y * h, p.visibility] for p in r.pose_landmarks.landmark])
        else:
            kps.append(None)
    pose.close()
    return ms, kps, decode_s + sum(ms) / 1000.0


def mp_run(mp_bin, path, out):
    t0 = time.perf_counter()
    r = subprocess.run(
        [mp_bin, "extract", path, "-o", out, "--single-person", "--all-joints"],
        capture_output=True,
        text=True,
        check=True,
    )
    wall = time.perf_counter() - t0
    fps = float(re.search(r"([0-9.]+) frames/s", r.stdout).group(1))
    z = np.load(out)
    return fps, z["positions"], z["confidence"], wall


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mp", default="target/release/mp")
    ap.add_argument("--out", help="JSON with the per-video figures")
    ap.add_argument("videos", nargs="+")
    a = ap.parse_args()
    rows = []
    all_d, all_v = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for v in a.videos:
            name = os.path.splitext(os.path.basename(v))[0]
            ms, kps, mediapipe_wall = mediapipe_run(v)
            fps, pos, conf, mp_wall = mp_run(a.mp, v, os.path.join(tmp, "kp.npz"))
            d, dv = [], []
            for t, k in enumerate(kps):
                if k is None or t >= len(pos) or not (conf[t] > 0).any():
                    continue
                k = np.asarray(k)
                e = np.linalg.norm(k[:, :2] - pos[t][:, :2], axis=1)
                d.extend(e.tolist())
                dv.extend(e[k[:, 2] > 0.5].tolist())
            all_d.extend(d)
            all_v.extend(dv)
            mp_fps = 1000.0 / float(np.median(ms))
            row = {
                "video": name,
                "frames": len(ms),
                "mp_fps": fps,
                "mediapipe_fps": mp_fps,
                "ratio": fps / mp_fps,
                "median_px": float(np.median(d)) if d else None,
                "median_px_visible": float(np.median(dv)) if dv else None,
                "mp_wall_s": mp_wall,
                "mediapipe_wall_s": mediapipe_wall,
            }
            rows.append(row)
            print(
                f"{name}: mp {fps:.1f} fps, MediaPipe {mp_fps:.1f} fps ({row['ratio']:.2f}x), "
                f"median {row['median_px'] if d else float('nan'):.2f} px "
                f"(visible {row['median_px_visible'] if dv else float('nan'):.2f} px)",
                flush=True,
            )
    mp_total = sum(r["frames"] / r["mp_fps"] for r in rows)
    mediapipe_total = sum(r["frames"] / r["mediapipe_fps"] for r in rows)
    frames = sum(r["frames"] for r in rows)
    summary = {
        "videos": len(rows),
        "frames": frames,
        "mp_fps": frames / mp_total,
        "mediapipe_fps": frames / mediapipe_total,
        "ratio": mediapipe_total / mp_total,
        "median_px": float(np.median(all_d)) if all_d else None,
        "median_px_visible": float(np.median(all_v)) if all_v else None,
        "mp_wall_s": sum(r["mp_wall_s"] for r in rows),
        "mediapipe_wall_s": sum(r["mediapipe_wall_s"] for r in rows),
        "definition": "fps: from each video's median per-frame time (decoding excluded), pooled as frames / sum(frames / fps); wall: the whole `mp extract` command (start, model loading, decoding on its own thread, every frame) against PyAV decoding plus every process() call; px: 33 landmarks on frames where both found a pose; px visible: those MediaPipe calls visible (> 0.5)",
    }
    print(json.dumps(summary, indent=1))
    if a.out:
        with open(a.out, "w") as f:
            json.dump({"summary": summary, "videos": rows}, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
