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

It also opens the batch dimension (input and outputs `N` instead of 1, and
the Reshapes that spell the batch as 1 take -1 or 0 for it), so that one run
takes the crops of several people. A batch of one gives the same values as
before.

usage: cut_mask.py IN.onnx OUT.onnx
"""

import os
import sys

import onnx
from onnx import numpy_helper, utils

KEEP = ["Identity", "Identity_1", "Identity_3", "Identity_4"]
MASK = "Identity_2"


def open_batch(model):
    """Make the batch dimension symbolic throughout `model` (in place)."""
    for value in list(model.graph.input) + list(model.graph.output):
        dims = value.type.tensor_type.shape.dim
        if not dims or dims[0].dim_value not in (0, 1):
            sys.exit(f"{value.name}: batch dimension is not 1")
        dims[0].dim_param = "N"
    # Inferred shapes say batch 1: drop them, ONNX Runtime infers them again.
    del model.graph.value_info[:]
    constants = {t.name: t for t in model.graph.initializer}
    for node in model.graph.node:
        if node.op_type != "Reshape" or node.input[1] not in constants:
            continue
        tensor = constants[node.input[1]]
        shape = numpy_helper.to_array(tensor).copy()
        if len(shape) == 0 or shape[0] != 1:
            continue
        # -1 infers the batch; 0 copies it where -1 is taken by another dim.
        shape[0] = 0 if -1 in shape[1:] else -1
        tensor.CopyFrom(numpy_helper.from_array(shape, tensor.name))


def main(src, dst):
    model = onnx.load(src)
    outputs = [o.name for o in model.graph.output]
    missing = [k for k in KEEP if k not in outputs]
    if missing:
        sys.exit(f"{src}: no output {', '.join(missing)} (its outputs: {', '.join(outputs)})")
    initialisers = {t.name for t in model.graph.initializer}
    inputs = [i.name for i in model.graph.input if i.name not in initialisers]
    cut = utils.Extractor(model).extract_model(inputs, KEEP)
    open_batch(cut)
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
