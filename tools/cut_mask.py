#!/usr/bin/env python3
"""Cut the segmentation-mask head off a BlazePose GHUM landmark model.

The landmark model has five outputs: landmarks (Identity), pose presence
(Identity_1), a 256x256 segmentation mask (Identity_2), landmark heatmaps
(Identity_3) and world landmarks (Identity_4). The pose estimators read every
output but the mask. ONNX Runtime runs every node of a graph whichever outputs
a run asks for, and the mask's decoder works at full resolution: about half of
the model's time. This tool keeps the sub-graph that computes the four outputs
read (onnx.utils.Extractor), so the same nodes compute the same values and the
mask's nodes are gone.

usage: cut_mask.py IN.onnx OUT.onnx
"""

import os
import sys

import onnx
from onnx import utils

KEEP = ["Identity", "Identity_1", "Identity_3", "Identity_4"]
MASK = "Identity_2"


def main(src, dst):
    model = onnx.load(src)
    outputs = [o.name for o in model.graph.output]
    missing = [k for k in KEEP if k not in outputs]
    if missing:
        sys.exit(f"{src}: no output {', '.join(missing)} (its outputs: {', '.join(outputs)})")
    initialisers = {t.name for t in model.graph.initializer}
    inputs = [i.name for i in model.graph.input if i.name not in initialisers]
    cut = utils.Extractor(model).extract_model(inputs, KEEP)
    onnx.checker.check_model(cut)
    if MASK in [o.name for o in cut.graph.output]:
        sys.exit(f"{src}: the mask output is still there after the cut")
    part = dst + ".part"
    onnx.save(cut, part)
    os.replace(part, dst)
    print(
        f"{os.path.basename(dst)}: {len(cut.graph.node)} of {len(model.graph.node)} nodes "
        f"(outputs {', '.join(KEEP)})"
    )


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
