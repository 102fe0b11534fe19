"""Scale-out: analyse a list of videos on a Ray cluster and write Parquet tables of videos and people.

Every worker keeps one ``motion_programs.Analyser`` (the pose model stays loaded between videos)
and runs exactly what ``mp run`` / ``mp batch`` run on each video: decoding, pose (every person in
view tracked), programs, repetition counts. Two tables are written:

- ``OUT/videos/``: one row per video, with the top-level (main person's) counts, the programs' text
  and the keypoints;
- ``OUT/people/``: one row per tracked person of each video (``path``, ``person`` id, ``main``,
  frames, mean box, ``total_repetitions``, counts, programs' text), as the ``people`` entries of
  ``loops.json``.

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

    def __init__(self, threads: int = 1, person: str = "all", max_people: int | None = None):
        import motion_programs as mp

        self.mp = mp
        self.analyser = mp.Analyser(threads=threads, person=person, max_people=max_people)

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
                    person=s.person,
                    people=json.dumps(person_entries(s)),
                )
            except self.mp.MpError as e:
                # Empty arrays rather than None: the columns keep one type across rows.
                row.update(status="failed", error=str(e), positions=[], positions_shape=[0, 0, 0],
                           confidence_scores=[], people="[]")
            row["seconds"] = time.perf_counter() - t0
            for k in COLUMNS:
                out[k].append(row[k])
        return out


def person_entries(summary) -> list[dict]:
    """Every tracked person of an analysis: the ``people`` entries of ``loops.json`` with the text
    of the person's programs (empty when the person was not analysed)."""
    out = []
    for p in summary.people:
        prog = summary.program_of(p["id"])
        abst = summary.abstract_program_of(p["id"])
        out.append(dict(p, program=prog.text if prog is not None else "",
                        abstract_program=abst.text if abst is not None else ""))
    return out


COLUMNS = [
    "path", "status", "error", "frames", "fps", "total_repetitions", "counts", "signal", "method",
    "confidence", "program", "abstract_program", "joint_names", "positions", "positions_shape",
    "confidence_scores", "person", "people", "seconds",
]


def people_schema():
    import pyarrow as pa

    return pa.schema([
        ("path", pa.string()),
        ("person", pa.int64()),
        ("main", pa.bool_()),
        ("first_frame", pa.int64()),
        ("last_frame", pa.int64()),
        ("frames_found", pa.int64()),
        ("box", pa.list_(pa.float64())),
        ("analysed", pa.bool_()),
        ("total_repetitions", pa.int64()),
        ("counts", pa.string()),
        ("signal", pa.string()),
        ("method", pa.string()),
        ("confidence", pa.float64()),
        ("program", pa.string()),
        ("abstract_program", pa.string()),
    ])


def people_rows(batch: dict):
    """Video rows → one row per tracked person (a pyarrow Table with a fixed schema, so that
    blocks without an analysed person still have the same column types)."""
    import pyarrow as pa

    rows = []
    for path, status, people in zip(batch["path"], batch["status"], batch["people"]):
        if status != "ok" or not people:
            continue
        for p in json.loads(people):
            reps = p["repetitions"] or {}
            rows.append({
                "path": str(path),
                "person": p["id"],
                "main": p["main"],
                "first_frame": p["first_frame"],
                "last_frame": p["last_frame"],
                "frames_found": p["frames_found"],
                "box": p["box"],
                "analysed": p["analysed"],
                "total_repetitions": reps.get("total"),
                "counts": json.dumps([i["count"] for i in reps["intervals"]] if reps else None),
                "signal": reps.get("signal"),
                "method": reps.get("method"),
                "confidence": reps.get("confidence"),
                "program": p["program"],
                "abstract_program": p["abstract_program"],
            })
    return pa.Table.from_pylist(rows, schema=people_schema())


def analyse_videos(paths: list[str], out_dir: str, workers: int = 2, threads: int = 1,
                   person: str = "all", max_people: int | None = None):
    """Runs the pipeline on every path with `workers` Ray actors and writes Parquet into
    `out_dir/videos` (one row per video) and `out_dir/people` (one row per tracked person).
    Returns both tables as pandas DataFrames (in input order; people by id within a video)."""
    import ray

    ds = ray.data.from_items([{"path": p} for p in paths], override_num_blocks=max(1, len(paths)))
    ds = ds.map_batches(
        Analyse,
        fn_constructor_kwargs={"threads": threads, "person": person, "max_people": max_people},
        batch_size=1,
        concurrency=workers,
        num_cpus=threads,
        batch_format="numpy",
    )
    ds = ds.materialize()
    ds.write_parquet(os.path.join(out_dir, "videos"))
    people = ds.select_columns(["path", "status", "people"]).map_batches(people_rows, batch_format="numpy")
    people = people.materialize()
    people.write_parquet(os.path.join(out_dir, "people"))
    order = {p: i for i, p in enumerate(paths)}
    videos_df = ds.to_pandas()
    videos_df = videos_df.sort_values("path", key=lambda s: s.map(order)).reset_index(drop=True)
    people_df = people.to_pandas()
    if people_df.empty:
        people_df = people_schema().empty_table().to_pandas()
    else:
        people_df["_order"] = people_df["path"].map(order)
        people_df = people_df.sort_values(["_order", "person"]).drop(columns="_order").reset_index(drop=True)
    return videos_df, people_df


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("source", help="a folder of videos or a text file of paths")
    ap.add_argument("--out", required=True, help="output folder for the Parquet files")
    ap.add_argument("--workers", type=int, default=2, help="Ray actors (default 2)")
    ap.add_argument("--threads", type=int, default=1, help="ONNX Runtime threads per actor (default 1)")
    ap.add_argument("--address", default=None, help="Ray cluster address (default: a local cluster)")
    ap.add_argument("--person", default="all",
                    help="whose motion is analysed: all (default), main or a person's id, as mp run --person")
    ap.add_argument("--max-people", type=int, default=None, help="most people tracked at once")
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
    df, people = analyse_videos(paths, a.out, a.workers, a.threads, a.person, a.max_people)
    wall = time.perf_counter() - t0
    frames = int(df["frames"].fillna(0).sum())
    for _, r in df.iterrows():
        print(f"{pathlib.Path(r['path']).name}: {r['status']} {r['total_repetitions']} repetitions {r['error'] or ''}")
        for _, p in people[people["path"] == r["path"]].iterrows():
            reps = "not analysed" if not p["analysed"] else f"{p['total_repetitions']} repetitions"
            print(f"  person {p['person']}{' (main)' if p['main'] else ''}: {reps}")
    print(f"{len(df)} videos, {len(people)} people, {frames} frames in {wall:.1f} s "
          f"({frames / max(wall, 1e-9):.1f} frames/s) → {a.out}/videos, {a.out}/people")
    return 0 if (df["status"] == "ok").all() else 1


if __name__ == "__main__":
    sys.exit(main())
