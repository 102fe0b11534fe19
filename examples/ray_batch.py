"""Scale-out: analyse a list of videos on a Ray cluster and write one Parquet row per video.

Every worker keeps one ``motion_programs.Analyser`` (the pose model stays loaded between videos)
and runs exactly what ``mp run`` / ``mp batch`` run on each video: decoding, pose, programs,
repetition counts. The rows hold the counts, the programs' text and the keypoints.

    .venv/bin/python examples/ray_batch.py VIDEO_DIR_OR_LIST --out results/ --workers 2

On a multi-node cluster, start Ray on each node (``ray start --head`` on one, ``ray start
--address HEAD:6379`` on the others), install the ``motion_programs`` wheel and ONNX Runtime on
every node (``bash scripts/python.sh``, or the wheel from ``target/wheels``), put the videos where
every node reads them (a shared file system or object store), and run this script with
``--address auto`` from any node. ``--threads`` sets the ONNX Runtime threads of one worker:
keep workers × threads at most the cores of a node.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys
import time

import numpy as np

VIDEO_EXTENSIONS = {".mp4", ".mov", ".avi", ".webm", ".mkv", ".m4v", ".mpg", ".mpeg", ".wmv", ".flv"}


def list_videos(source: str) -> list[str]:
    """The videos of a folder (sorted), or the paths listed in a text file (one per line)."""
    p = pathlib.Path(source)
    if p.is_dir():
        return sorted(str(f.resolve()) for f in p.iterdir() if f.suffix.lower() in VIDEO_EXTENSIONS)
    lines = [ln.strip() for ln in p.read_text().splitlines()]
    return [str((p.parent / ln).resolve()) for ln in lines if ln and not ln.startswith("#")]


class Analyse:
    """A Ray Data callable class: constructed once per worker, called on batches of paths."""

    def __init__(self, threads: int = 1):
        import motion_programs as mp

        self.mp = mp
        self.analyser = mp.Analyser(threads=threads)

    def __call__(self, batch: dict) -> dict:
        out: dict[str, list] = {k: [] for k in COLUMNS}
        for path in batch["path"]:
            t0 = time.perf_counter()
            row = {k: None for k in COLUMNS}
            row["path"] = str(path)
            try:
                s = self.analyser.analyse(str(path))
                c = s.counts
                t = s.track
                row.update(
                    status="ok",
                    error="",
                    frames=s.frames,
                    fps=t.fps,
                    total_repetitions=c.total,
                    counts=json.dumps([i["count"] for i in c.intervals]),
                    signal=c.signal,
                    method=c.method,
                    confidence=c.confidence,
                    program=s.program.text if s.program is not None else "",
                    abstract_program=s.abstract_program.text if s.abstract_program is not None else "",
                    joint_names=json.dumps(t.joint_names),
                    positions=t.positions.astype(np.float32).ravel().tolist(),
                    positions_shape=list(t.positions.shape),
                    confidence_scores=t.confidence.astype(np.float32).ravel().tolist(),
                )
            except self.mp.MpError as e:
                row.update(status="failed", error=str(e))
            row["seconds"] = time.perf_counter() - t0
            for k in COLUMNS:
                out[k].append(row[k])
        return out


COLUMNS = [
    "path", "status", "error", "frames", "fps", "total_repetitions", "counts", "signal", "method",
    "confidence", "program", "abstract_program", "joint_names", "positions", "positions_shape",
    "confidence_scores", "seconds",
]


def analyse_videos(paths: list[str], out_dir: str, workers: int = 2, threads: int = 1):
    """Runs the pipeline on every path with `workers` Ray actors and writes Parquet into `out_dir`.
    Returns the rows as a pandas DataFrame (in input order)."""
    import ray

    ds = ray.data.from_items([{"path": p} for p in paths], override_num_blocks=max(1, len(paths)))
    ds = ds.map_batches(
        Analyse,
        fn_constructor_kwargs={"threads": threads},
        batch_size=1,
        concurrency=workers,
        num_cpus=threads,
        batch_format="numpy",
    )
    ds = ds.materialize()
    ds.write_parquet(out_dir)
    df = ds.to_pandas()
    order = {p: i for i, p in enumerate(paths)}
    return df.sort_values("path", key=lambda s: s.map(order)).reset_index(drop=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("source", help="a folder of videos or a text file of paths")
    ap.add_argument("--out", required=True, help="output folder for the Parquet files")
    ap.add_argument("--workers", type=int, default=2, help="Ray actors (default 2)")
    ap.add_argument("--threads", type=int, default=1, help="ONNX Runtime threads per actor (default 1)")
    ap.add_argument("--address", default=None, help="Ray cluster address (default: a local cluster)")
    a = ap.parse_args(argv)
    import ray

    paths = list_videos(a.source)
    if not paths:
        print(f"no video in {a.source}", file=sys.stderr)
        return 2
    if a.address:
        ray.init(address=a.address)
    else:
        ray.init(num_cpus=max(a.workers * a.threads, os.cpu_count() or 1))
    t0 = time.perf_counter()
    df = analyse_videos(paths, a.out, a.workers, a.threads)
    wall = time.perf_counter() - t0
    frames = int(df["frames"].fillna(0).sum())
    for _, r in df.iterrows():
        print(f"{pathlib.Path(r['path']).name}: {r['status']} {r['total_repetitions']} repetitions {r['error'] or ''}")
    print(f"{len(df)} videos, {frames} frames in {wall:.1f} s ({frames / max(wall, 1e-9):.1f} frames/s) → {a.out}")
    return 0 if (df["status"] == "ok").all() else 1


if __name__ == "__main__":
    sys.exit(main())
