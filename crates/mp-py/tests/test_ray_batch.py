"""The Ray Data pipeline (examples/ray_batch.py) on a local Ray cluster gives the same per-video
and per-person results as `mp batch` on the same videos."""

import importlib.util
import json
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
# Four short QUVA videos (124–158 frames), two per actor.
VIDEOS = ["007_pommel_practice", "009_pommel_practice", "020_fitness", "023_fitness"]


def load_example():
    spec = importlib.util.spec_from_file_location("ray_batch", ROOT / "examples" / "ray_batch.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_ray_pipeline_equals_mp_batch(data, mp_bin, tmp_path):
    ray = pytest.importorskip("ray")
    paths = [str(data(f"quva_repetition/videos/{v}.mp4")) for v in VIDEOS]
    listing = tmp_path / "videos.txt"
    listing.write_text("\n".join(paths) + "\n")
    # mp batch, two jobs.
    out = subprocess.run(
        [str(mp_bin), "batch", str(listing), "--out", str(tmp_path / "batch"), "--jobs", "2", "--no-video", "--quiet"],
        capture_output=True, text=True,
    )
    assert out.returncode == 0, out.stderr
    manifest = {}
    for line in (tmp_path / "batch" / "manifest.jsonl").read_text().splitlines():
        item = json.loads(line)
        manifest[str(pathlib.Path(item["input"]).resolve())] = item
    assert len(manifest) == len(paths)
    # The Ray pipeline on a local two-CPU cluster, two actors.
    rb = load_example()
    ray.init(num_cpus=2, include_dashboard=False, ignore_reinit_error=True)
    try:
        df, people = rb.analyse_videos(paths, str(tmp_path / "parquet"), workers=2, threads=1)
    finally:
        ray.shutdown()
    assert list(df["path"]) == paths
    assert list((tmp_path / "parquet" / "videos").glob("*.parquet")), "no Parquet of videos written"
    assert list((tmp_path / "parquet" / "people").glob("*.parquet")), "no Parquet of people written"
    for _, row in df.iterrows():
        item = manifest[str(pathlib.Path(row["path"]).resolve())]
        assert row["status"] == item["status"] == "ok", (row["error"], item.get("error"))
        assert row["total_repetitions"] == item["total_repetitions"], row["path"]
        assert json.loads(row["counts"]) == item["counts"], row["path"]
        folder = pathlib.Path(item["output"])
        if not folder.is_absolute():
            folder = tmp_path / "batch" / folder
        assert row["program"] == (folder / "program.txt").read_text(), row["path"]
        n, j, d = row["positions_shape"]
        assert n == row["frames"] and len(row["positions"]) == n * j * d
        # One row per tracked person, as loops.json's `people` list; the main person's are the
        # video's top-level results, everyone else's programs are under people/<id>/.
        loops = json.loads((folder / "loops.json").read_text())
        mine = people[people["path"] == row["path"]]
        assert list(mine["person"]) == [p["id"] for p in loops["people"]], row["path"]
        assert len(mine) >= 1 and mine["main"].sum() == 1, row["path"]
        assert row["person"] == loops["person"] == mine[mine["main"]]["person"].iloc[0]
        for (_, r), p in zip(mine.iterrows(), loops["people"]):
            for k in ["main", "first_frame", "last_frame", "frames_found", "analysed"]:
                assert r[k] == p[k], (row["path"], p["id"], k)
            assert list(r["box"]) == p["box"], (row["path"], p["id"])
            if p["analysed"]:
                assert r["total_repetitions"] == p["repetitions"]["total"], (row["path"], p["id"])
                counts = [i["count"] for i in p["repetitions"]["intervals"]]
                assert json.loads(r["counts"]) == counts, (row["path"], p["id"])
                prog = folder / "program.txt" if p["main"] else folder / "people" / str(p["id"]) / "program.txt"
                assert r["program"] == prog.read_text(), (row["path"], p["id"])
            if p["main"]:
                assert r["total_repetitions"] == row["total_repetitions"]
