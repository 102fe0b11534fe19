#!/usr/bin/env python3
"""Replace every DENSIFY op of a TFLite model by a dense constant.

Some TFLite models (the BlazePose person detector among them) store weights as
sparse fp16 constants followed by a DENSIFY op. tf2onnx cannot convert DENSIFY.
This tool runs the model once with TFLite's reference kernels, reads the dense
output of each DENSIFY op, stores that value as a constant buffer of the op's
output tensor and removes the op. The rewritten model computes exactly the same
function (checked at the end: max |difference| of every output on a random input).

usage: densify_tflite.py IN.tflite OUT.tflite
"""

import sys

import numpy as np
import tensorflow as tf
from tensorflow.lite.python import schema_py_generated as schema
from tensorflow.lite.tools import flatbuffer_utils


def run_model(path_or_bytes, inputs, preserve=False):
    kwargs = dict(
        experimental_op_resolver_type=tf.lite.experimental.OpResolverType.BUILTIN_REF,
        experimental_preserve_all_tensors=preserve,
    )
    if isinstance(path_or_bytes, bytes):
        interp = tf.lite.Interpreter(model_content=path_or_bytes, **kwargs)
    else:
        interp = tf.lite.Interpreter(model_path=path_or_bytes, **kwargs)
    interp.allocate_tensors()
    for det, value in zip(interp.get_input_details(), inputs):
        interp.set_tensor(det["index"], value)
    interp.invoke()
    return interp


def random_inputs(interp, seed=0):
    rng = np.random.default_rng(seed)
    out = []
    for det in interp.get_input_details():
        shape, dtype = det["shape"], det["dtype"]
        if np.issubdtype(dtype, np.floating):
            out.append(rng.uniform(-1.0, 1.0, size=shape).astype(dtype))
        else:
            out.append(rng.integers(0, 255, size=shape).astype(dtype))
    return out


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    src, dst = sys.argv[1], sys.argv[2]
    model = flatbuffer_utils.read_model(src)

    probe = tf.lite.Interpreter(model_path=src)
    probe.allocate_tensors()
    inputs = random_inputs(probe)
    interp = run_model(src, inputs, preserve=True)

    n_removed = 0
    for sg_index, subgraph in enumerate(model.subgraphs):
        keep = []
        rewired = {}
        for op in subgraph.operators:
            code = model.operatorCodes[op.opcodeIndex]
            builtin = max(code.builtinCode, code.deprecatedBuiltinCode)
            if builtin != schema.BuiltinOperator.DENSIFY:
                keep.append(op)
                continue
            if sg_index != 0:
                sys.exit("DENSIFY outside the main subgraph is not supported")
            in_index, out_index = op.inputs[0], op.outputs[0]
            dense = interp.get_tensor(out_index)
            sparse = subgraph.tensors[in_index]
            # The sparse constant becomes the dense constant ...
            model.buffers[sparse.buffer].data = np.frombuffer(dense.tobytes(), dtype=np.uint8).copy()
            sparse.sparsity = None
            sparse.shape = np.array(dense.shape, dtype=np.int32)
            # ... and every consumer of the DENSIFY output reads it directly.
            rewired[out_index] = in_index
            n_removed += 1
        for op in keep:
            op.inputs = np.array([rewired.get(int(i), int(i)) for i in op.inputs], dtype=np.int32)
        subgraph.outputs = np.array([rewired.get(int(i), int(i)) for i in subgraph.outputs], dtype=np.int32)
        subgraph.operators = keep

    flatbuffer_utils.write_model(model, dst)

    # Check: same outputs on the same input.
    a = run_model(src, inputs)
    b = run_model(dst, inputs)
    worst = 0.0
    for da, db in zip(a.get_output_details(), b.get_output_details()):
        va = a.get_tensor(da["index"]).astype(np.float64)
        vb = b.get_tensor(db["index"]).astype(np.float64)
        worst = max(worst, float(np.max(np.abs(va - vb))))
    print(f"densify: removed {n_removed} DENSIFY ops; max |difference| of outputs = {worst:g}")
    if worst > 0.0:
        sys.exit("densify: the rewritten model does not reproduce the original")


if __name__ == "__main__":
    main()
