"""From a video to a plot of its counted repetitions.

    .venv/bin/python examples/plot_repetitions.py VIDEO.mp4 -o repetitions.png

Runs the same analysis as `mp run` (pose, programs, repetition counts), then plots the vertical
position of the most moving joint over time, the executed program over it, and each counted
repetition as a shaded band.
"""

from __future__ import annotations

import argparse
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import motion_programs as mp  # noqa: E402


def plot(video: str, out: str) -> mp.Counts:
    s = mp.Analyser(report=False, overlay_video=False).analyse(video)
    track, counts = s.track, s.counts
    t = np.arange(track.n_frames) / track.fps
    pos, conf = track.positions, track.confidence
    # The joint whose vertical position varies most where it is seen.
    y = np.where(conf > 0, pos[:, :, 1], np.nan)
    j = int(np.nanargmax(np.nanstd(y, axis=0))) if np.isfinite(y).any() else 0
    fig, ax = plt.subplots(figsize=(10, 3.5))
    ax.plot(t, y[:, j], ".", ms=3, color="tab:orange", label=f"{track.joint_names[j]} (keypoints)")
    if s.program is not None:
        ax.plot(t, s.program.execute()[:, j, 1], color="tab:pink", lw=1.5, label="program")
    for iv in counts.intervals:
        # Each repetition's first and last frame (both included).
        for k, (a, last) in enumerate(iv["repetitions"]):
            e = last + 1
            ax.axvspan(a / track.fps, e / track.fps, color="tab:blue", alpha=0.08 + 0.08 * (k % 2))
            ax.text((a + e) / 2 / track.fps, 0.97, str(k + 1), transform=ax.get_xaxis_transform(),
                    ha="center", va="top", fontsize=8, color="tab:blue")
    ax.invert_yaxis()
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"y ({track.units})")
    ax.set_title(f"{counts.total} repetitions (from the {counts.signal}, {counts.method}, "
                 f"confidence {counts.confidence:.2f})")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return counts


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("video")
    ap.add_argument("-o", "--out", default="repetitions.png")
    a = ap.parse_args(argv)
    c = plot(a.video, a.out)
    print(f"{c.total} repetitions → {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
