#!/usr/bin/env python3
"""Writes crates/mp-pose/testdata/model_fixtures.json: outputs of each pose
model on a fixed synthetic input, computed with Python onnxruntime. The Rust
tests feed the same input through `ort` and compare.

Input pattern (all models): value(y, x, c) = (3x + 5y + 50c) mod 256, as uint8
for MoveNet, / 127.5 - 1 for the detector, / 255 for the landmark models.

usage: make_pose_fixtures.py MODEL_DIR OUT.json   (run in .cache/venv-models)
"""

import json
import sys

import numpy as np
import onnxruntime as ort


def pattern(n):
    y, x, c = np.meshgrid(np.arange(n), np.arange(n), np.arange(3), indexing="ij")
    return ((3 * x + 5 * y + 50 * c) % 256).astype(np.uint8)[None]


def session(path):
    so = ort.SessionOptions()
    so.intra_op_num_threads = 1
    return ort.InferenceSession(path, so, providers=["CPUExecutionProvider"])


def flat(a, idx):
    a = np.asarray(a).reshape(-1)
    return [float(a[i]) for i in idx]


def main():
    model_dir, out = sys.argv[1], sys.argv[2]
    fx = {"pattern": "(3x + 5y + 50c) mod 256", "onnxruntime": ort.__version__}

    s = session(f"{model_dir}/pose_detection.onnx")
    x = pattern(224).astype(np.float32) / np.float32(127.5) - np.float32(1.0)
    boxes, scores = s.run(["Identity", "Identity_1"], {"input_1": x})
    sc = scores.reshape(-1)
    best = int(np.argmax(sc))
    fx["detector"] = {
        "boxes_first_36": flat(boxes, range(36)),
        "score_idx": [0, 100, 1000, 1567, 1568, 2253, best],
        "scores": flat(sc, [0, 100, 1000, 1567, 1568, 2253, best]),
        "best_index": best,
        "best_boxes": flat(boxes.reshape(-1, 12)[best], range(12)),
    }

    x = pattern(256).astype(np.float32) / np.float32(255.0)
    for name in ["full", "lite"]:
        s = session(f"{model_dir}/pose_landmark_{name}.onnx")
        lm, pres, seg, hm, world = s.run(["Identity", "Identity_1", "Identity_2", "Identity_3", "Identity_4"], {"input_1": x})
        hm_idx = [0, 12345, 80000, 159743]
        seg_idx = [0, 32896, 65535]
        fx[f"landmark_{name}"] = {
            "landmarks": flat(lm, range(195)),
            "presence": float(pres.reshape(-1)[0]),
            "world": flat(world, range(117)),
            "heatmap_idx": hm_idx,
            "heatmap": flat(hm, hm_idx),
            "segmentation_idx": seg_idx,
            "segmentation": flat(seg, seg_idx),
        }

    s = session(f"{model_dir}/movenet_singlepose_lightning_int8.onnx")
    (kp,) = s.run(["StatefulPartitionedCall:0"], {"serving_default_input:0": pattern(192)})
    fx["movenet"] = {"keypoints": flat(kp, range(51))}

    with open(out, "w") as f:
        json.dump(fx, f, indent=1)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
