#!/usr/bin/env python3
"""Check that a converted ONNX model computes what the original TFLite model computes.

Builds the model's input from a real photo (letterboxed square resize, the
model's value range), runs TFLite (reference kernels, no delegate) and ONNX
Runtime, and compares every output by position. Prints one JSON line per model
and exits 1 when an output differs by more than its tolerance.

usage: verify_onnx_vs_tflite.py IMAGE.jpg MODEL.tflite MODEL.onnx [--tol-scale X]
"""

import json
import sys

import numpy as np
import onnxruntime as ort
import tensorflow as tf
from PIL import Image


def letterbox(img, size):
    w, h = img.size
    s = max(w, h)
    canvas = Image.new("RGB", (s, s))
    canvas.paste(img, ((s - w) // 2, (s - h) // 2))
    return np.asarray(canvas.resize((size, size), Image.BILINEAR))


def make_input(img, shape, dtype):
    _, h, w, _ = shape
    px = letterbox(img, h)
    if dtype == np.uint8:
        return px[None].astype(np.uint8)
    # Detector (224) takes [-1, 1]; landmark models (256) take [0, 1].
    if h == 224:
        return (px[None].astype(np.float32) / 127.5 - 1.0).astype(np.float32)
    return (px[None].astype(np.float32) / 255.0).astype(np.float32)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    tol_scale = 1.0
    if "--tol-scale" in sys.argv:
        tol_scale = float(sys.argv[sys.argv.index("--tol-scale") + 1])
        args.remove(sys.argv[sys.argv.index("--tol-scale") + 1])
    if len(args) != 3:
        sys.exit(__doc__)
    image_path, tflite_path, onnx_path = args
    img = Image.open(image_path).convert("RGB")

    interp = tf.lite.Interpreter(
        model_path=tflite_path,
        experimental_op_resolver_type=tf.lite.experimental.OpResolverType.BUILTIN_WITHOUT_DEFAULT_DELEGATES,
    )
    interp.allocate_tensors()
    det = interp.get_input_details()[0]
    x = make_input(img, det["shape"], det["dtype"])
    interp.set_tensor(det["index"], x)
    interp.invoke()
    tfl = [interp.get_tensor(d["index"]) for d in interp.get_output_details()]

    sess = ort.InferenceSession(onnx_path, providers=["CPUExecutionProvider"])
    onx = sess.run(None, {sess.get_inputs()[0].name: x})

    report = {"model": onnx_path, "image": image_path, "outputs": []}
    ok = True
    # Outputs correspond by shape (tf2onnx keeps the order of the TFLite outputs).
    for i, (a, b) in enumerate(zip(tfl, onx)):
        a = np.asarray(a, dtype=np.float64)
        b = np.asarray(b, dtype=np.float64).reshape(a.shape)
        diff = float(np.max(np.abs(a - b))) if a.size else 0.0
        mag = float(np.max(np.abs(a))) if a.size else 0.0
        # Tolerance: relative to the output's magnitude (raw regressors reach ±700, segmentation logits ±1700).
        tol = tol_scale * max(1e-2, 2e-4 * mag)
        if det["dtype"] == np.uint8:
            tol = tol_scale * 0.3  # int8 graphs: TFLite's own kernels disagree by ~0.25
        passed = diff <= tol
        ok &= passed
        report["outputs"].append(
            {"index": i, "shape": list(a.shape), "max_abs_diff": diff, "max_abs": mag, "tol": tol, "ok": passed}
        )
    report["ok"] = ok
    print(json.dumps(report))
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
