"""Convert MediaPipe's BlazePose TFLite models (from the ``mediapipe==0.10.21`` wheel) to ONNX.

Run it in its own virtual environment, never in the project's (TensorFlow is not a project
dependency)::

    python3.11 -m venv /work/convert-venv
    /work/convert-venv/bin/pip install 'tensorflow-cpu==2.21.*' 'tf2onnx==1.17.*' onnxruntime \
        opencv-python-headless
    /work/convert-venv/bin/python tools/convert_blazepose.py [--wheel mediapipe-0.10.21-....whl]

Without ``--wheel`` the script runs ``pip download mediapipe==0.10.21 --no-deps`` (the only
network access; everything after it is offline). It

1. records the sha256 of the wheel and of the two ``.tflite`` files taken from it;
2. converts ``pose_landmark_full.tflite`` directly with tf2onnx, keeping the outputs the
   runtime uses (landmarks, pose flag, heatmap, world landmarks; the segmentation mask head is
   dropped, which removes its decoder from the graph);
3. works around the detector's DENSIFY ops (38 weights stored sparse; tf2onnx fails on them):
   the dense weights are read back from the TFLite interpreter with the default delegate
   turned off (with XNNPACK on, the values came back wrong) and written into the flatbuffer as
   plain constants, the DENSIFY ops removed, and the patched model converted;
4. checks each ONNX model against TFLite on identical random and real inputs and writes the
   maximum differences, versions and hashes to ``PROVENANCE.json`` beside the models.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import platform
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

WHEEL_SPEC = "mediapipe==0.10.21"
DETECTOR_IN_WHEEL = "mediapipe/modules/pose_detection/pose_detection.tflite"
LANDMARK_IN_WHEEL = "mediapipe/modules/pose_landmark/pose_landmark_full.tflite"
LICENSE_IN_WHEEL = "mediapipe-0.10.21.dist-info/LICENSE"
ROOT = Path(__file__).resolve().parents[1]
OUT_DIR = ROOT / "features" / "pose_estimation" / "models"
DETECTOR_ONNX = "pose_detection.onnx"
LANDMARK_ONNX = "pose_landmark_full.onnx"
# Outputs of pose_landmark_full kept in the ONNX model (Identity_2, the segmentation mask, is
# not used by the pose pipeline).
LANDMARK_OUTPUTS = ["Identity", "Identity_1", "Identity_3", "Identity_4"]
OPSET = 17


def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def get_wheel(wheel: Path | None, workdir: Path) -> Path:
    if wheel is not None:
        return wheel
    subprocess.run(
        [sys.executable, "-m", "pip", "download", WHEEL_SPEC, "--no-deps", "-d", str(workdir)],
        check=True,
    )
    found = sorted(workdir.glob("mediapipe-0.10.21-*.whl"))
    if not found:
        raise SystemExit("pip download gave no mediapipe 0.10.21 wheel")
    return found[0]


def densify_detector(src: Path, dst: Path) -> int:
    """Write ``src`` with every DENSIFY op replaced by its dense output as a constant.

    Returns the number of DENSIFY ops removed.
    """
    import tensorflow as tf
    from tensorflow.lite.python import schema_py_generated as schema
    from tensorflow.lite.tools import flatbuffer_utils

    model = flatbuffer_utils.read_model(str(src))
    graph = model.subgraphs[0]
    densify_code = {
        i
        for i, code in enumerate(model.operatorCodes)
        if max(code.builtinCode, code.deprecatedBuiltinCode) == schema.BuiltinOperator.DENSIFY
    }
    densify_ops = [op for op in graph.operators if op.opcodeIndex in densify_code]
    # The default delegate (XNNPACK) gave wrong dense values here; the reference kernels do not.
    interpreter = tf.lite.Interpreter(
        model_path=str(src),
        experimental_op_resolver_type=tf.lite.experimental.OpResolverType.BUILTIN_WITHOUT_DEFAULT_DELEGATES,
        experimental_preserve_all_tensors=True,
    )
    interpreter.allocate_tensors()
    inp = interpreter.get_input_details()[0]
    interpreter.set_tensor(inp["index"], np.zeros(inp["shape"], np.float32))
    interpreter.invoke()
    for op in densify_ops:
        out_index = int(op.outputs[0])
        dense = np.ascontiguousarray(interpreter.get_tensor(out_index))
        tensor = graph.tensors[out_index]
        expected = tuple(int(d) for d in tensor.shape)
        if dense.shape != expected:
            raise SystemExit(f"DENSIFY output {out_index}: shape {dense.shape} != {expected}")
        buffer = schema.BufferT()
        buffer.data = np.frombuffer(dense.tobytes(), dtype=np.uint8)
        model.buffers.append(buffer)
        tensor.buffer = len(model.buffers) - 1
        # tf2onnx parses every constant tensor; the now unused sparse input would fail to
        # reshape, so it is emptied (buffer 0 is the flatbuffer's empty buffer by convention).
        sparse = graph.tensors[int(op.inputs[0])]
        sparse.buffer = 0
        sparse.sparsity = None
    graph.operators = [op for op in graph.operators if op.opcodeIndex not in densify_code]
    flatbuffer_utils.write_model(model, str(dst))
    return len(densify_ops)


def convert(tflite: Path, onnx_path: Path, outputs: list[str] | None) -> None:
    import onnx
    import tf2onnx

    model_proto, _ = tf2onnx.convert.from_tflite(str(tflite), opset=OPSET)
    if outputs is not None:
        keep = set(outputs)
        kept = [o for o in model_proto.graph.output if o.name in keep]
        del model_proto.graph.output[:]
        model_proto.graph.output.extend(kept)
        # Drop nodes that no kept output depends on (the segmentation decoder).
        needed = set(outputs)
        nodes = list(model_proto.graph.node)
        live = []
        for node in reversed(nodes):
            if any(o in needed for o in node.output):
                live.append(node)
                needed.update(node.input)
        del model_proto.graph.node[:]
        model_proto.graph.node.extend(reversed(live))
        used = {i for n in live for i in n.input}
        inits = [t for t in model_proto.graph.initializer if t.name in used]
        del model_proto.graph.initializer[:]
        model_proto.graph.initializer.extend(inits)
    canonical_order(model_proto)
    canonicalize_names(model_proto)
    model_proto.producer_name = "posecbr tools/convert_blazepose.py (tf2onnx)"
    onnx.checker.check_model(model_proto)
    onnx.save(model_proto, str(onnx_path))


def canonical_order(model_proto: object) -> None:
    """Sort the nodes topologically in an order that depends only on the graph itself.

    tf2onnx emits a valid topological order, but which one varies from run to run (it walks
    sets). Each value gets a structural hash (a graph input: its name; an initializer: its
    dtype, shape and bytes; a node output: the node's op, attributes and its inputs' hashes),
    and Kahn's algorithm always takes the ready node with the smallest hash.
    """
    graph = model_proto.graph  # type: ignore[attr-defined]
    nodes = list(graph.node)
    hashes = _StructuralHashes(graph, nodes)
    order = _smallest_hash_first(nodes, hashes.producer, hashes.all_nodes())
    copies = [type(n)() for n in order]
    for dst, src in zip(copies, order, strict=True):
        dst.CopyFrom(src)
    del graph.node[:]
    graph.node.extend(copies)


class _StructuralHashes:
    """Hashes of the values and nodes of an ONNX graph that depend only on its structure."""

    def __init__(self, graph: Any, nodes: list[Any]) -> None:
        from onnx import numpy_helper

        self.nodes = nodes
        self.value_hash: dict[str, str] = {"": "none"}
        for v in graph.input:
            self.value_hash[v.name] = hashlib.sha256(b"input:" + v.name.encode()).hexdigest()
        for init in graph.initializer:
            arr = numpy_helper.to_array(init)
            h = hashlib.sha256(f"init:{arr.dtype}:{arr.shape}:".encode() + arr.tobytes())
            self.value_hash[init.name] = h.hexdigest()
        self.producer = {out: i for i, n in enumerate(nodes) for out in n.output if out}
        self.node_hash: dict[int, str] = {}

    def all_nodes(self) -> list[str]:
        """Every node's hash, by position."""
        # a node's hash recurses through its inputs' producers: as deep as the graph
        sys.setrecursionlimit(max(10000, sys.getrecursionlimit()))
        return [self.node(i) for i in range(len(self.nodes))]

    def node(self, i: int) -> str:
        """Node ``i``'s hash (op, attributes, inputs' hashes); its outputs' hashes with it."""
        if i in self.node_hash:
            return self.node_hash[i]
        node = self.nodes[i]
        h = hashlib.sha256(f"{node.domain}:{node.op_type}:".encode())
        for attr in sorted(node.attribute, key=lambda a: a.name):
            h.update(attr.SerializeToString(deterministic=True))
        for name in node.input:
            h.update(self.value(name).encode())
        self.node_hash[i] = h.hexdigest()
        for k, out in enumerate(node.output):
            self.value_hash[out] = hashlib.sha256(f"{self.node_hash[i]}:{k}".encode()).hexdigest()
        return self.node_hash[i]

    def value(self, name: str) -> str:
        if name not in self.value_hash:
            self.node(self.producer[name])
        return self.value_hash[name]


def _smallest_hash_first(
    nodes: list[Any], producer: dict[str, int], node_hash: list[str]
) -> list[Any]:
    """Kahn's algorithm over ``nodes``, always taking the ready node with the smallest hash."""
    import heapq

    deps = {i: {producer[x] for x in n.input if x in producer} for i, n in enumerate(nodes)}
    users: dict[int, list[int]] = {i: [] for i in range(len(nodes))}
    for i, d in deps.items():
        for j in d:
            users[j].append(i)
    waiting = {i: len(d) for i, d in deps.items()}
    ready = [(node_hash[i], i) for i, w in waiting.items() if w == 0]
    heapq.heapify(ready)
    order = []
    while ready:
        _, i = heapq.heappop(ready)
        order.append(nodes[i])
        for j in users[i]:
            waiting[j] -= 1
            if waiting[j] == 0:
                heapq.heappush(ready, (node_hash[j], j))
    if len(order) != len(nodes):
        raise SystemExit("graph has a cycle")
    return order


def canonicalize_names(model_proto: object) -> None:
    """Rename nodes and internal tensors by position, so that reruns give identical bytes.

    tf2onnx numbers the names it makes from a process-wide counter whose values vary between
    runs; with :func:`canonical_order` first, the graph itself does not.
    """
    graph = model_proto.graph  # type: ignore[attr-defined]
    keep = {v.name for v in graph.input} | {v.name for v in graph.output}
    inits = {init.name: init for init in graph.initializer}
    rename: dict[str, str] = {}
    order: list[str] = []  # initializers by first use
    for i, node in enumerate(graph.node):
        node.name = f"n{i}"
        for name in node.input:
            if name in inits and name not in keep and name not in rename:
                rename[name] = f"w{len(order)}"
                order.append(name)
        for out in node.output:
            if out and out not in keep and out not in rename:
                rename[out] = f"t{len(rename) - len(order)}"
    ordered = [inits[n] for n in order] + [v for n, v in inits.items() if n not in rename]
    copies = [type(v)() for v in ordered]
    for dst, src in zip(copies, ordered, strict=True):
        dst.CopyFrom(src)
    del graph.initializer[:]
    graph.initializer.extend(copies)
    for init in graph.initializer:
        init.name = rename.get(init.name, init.name)
    for node in graph.node:
        node.input[:] = [rename.get(x, x) for x in node.input]
        node.output[:] = [rename.get(x, x) for x in node.output]
    for info in graph.value_info:
        info.name = rename.get(info.name, info.name)


def compare(tflite: Path, onnx_path: Path, inputs: list[np.ndarray]) -> dict[str, float]:
    """Max |ONNX - TFLite| per output name over ``inputs``."""
    import onnxruntime as ort
    import tensorflow as tf

    interpreter = tf.lite.Interpreter(
        model_path=str(tflite),
        experimental_op_resolver_type=tf.lite.experimental.OpResolverType.BUILTIN_WITHOUT_DEFAULT_DELEGATES,
    )
    interpreter.allocate_tensors()
    inp = interpreter.get_input_details()[0]
    outs = {d["name"]: d["index"] for d in interpreter.get_output_details()}
    sess = ort.InferenceSession(str(onnx_path), providers=["CPUExecutionProvider"])
    onnx_in = sess.get_inputs()[0].name
    onnx_outs = [o.name for o in sess.get_outputs()]
    worst: dict[str, float] = {}
    for x in inputs:
        interpreter.set_tensor(inp["index"], x)
        interpreter.invoke()
        got = sess.run(onnx_outs, {onnx_in: x})
        for name, value in zip(onnx_outs, got, strict=True):
            ref = interpreter.get_tensor(outs[name])
            diff = float(np.max(np.abs(ref - value)))
            worst[name] = max(worst.get(name, 0.0), diff)
    return worst


REAL_PHOTOS = ("basketball1.png", "messi5.jpg")


def real_inputs(size: int, lo: float, hi: float) -> list[np.ndarray]:
    """Real photos from ../shared/data/media resized to the model input."""
    import cv2

    images = []
    media = ROOT.parent / "shared" / "data" / "media"
    for name in REAL_PHOTOS:
        path = media / name
        if not path.exists():
            raise SystemExit(f"{path} is missing: the check needs the real photos")
        img = cv2.cvtColor(cv2.imread(str(path)), cv2.COLOR_BGR2RGB)
        img = cv2.resize(img, (size, size), interpolation=cv2.INTER_AREA)
        x = img.astype(np.float32) / 255.0 * (hi - lo) + lo
        images.append(x[None])
    return images


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wheel", type=Path, help="the mediapipe 0.10.21 wheel (else downloaded)")
    parser.add_argument("--out", type=Path, default=OUT_DIR)
    args = parser.parse_args()
    import onnx
    import onnxruntime
    import tensorflow as tf
    import tf2onnx

    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        wheel = get_wheel(args.wheel, tmp)
        with zipfile.ZipFile(wheel) as zf:
            for member in (DETECTOR_IN_WHEEL, LANDMARK_IN_WHEEL, LICENSE_IN_WHEEL):
                zf.extract(member, tmp)
        detector = tmp / DETECTOR_IN_WHEEL
        landmark = tmp / LANDMARK_IN_WHEEL
        (args.out / "LICENSE").write_bytes((tmp / LICENSE_IN_WHEEL).read_bytes())

        patched = tmp / "pose_detection_dense.tflite"
        n_densify = densify_detector(detector, patched)
        convert(patched, args.out / DETECTOR_ONNX, None)
        convert(landmark, args.out / LANDMARK_ONNX, LANDMARK_OUTPUTS)

        rng = np.random.default_rng(0)
        det_inputs = [rng.uniform(-1, 1, (1, 224, 224, 3)).astype(np.float32)]
        det_inputs += real_inputs(224, -1.0, 1.0)
        lm_inputs = [rng.uniform(0, 1, (1, 256, 256, 3)).astype(np.float32)]
        lm_inputs += real_inputs(256, 0.0, 1.0)
        # The detector is compared with the ORIGINAL (sparse) model: it checks the densify
        # step too.
        det_diff = compare(detector, args.out / DETECTOR_ONNX, det_inputs)
        lm_diff = compare(landmark, args.out / LANDMARK_ONNX, lm_inputs)

        provenance = {
            "source_package": WHEEL_SPEC,
            "wheel": {"file": wheel.name, "sha256": sha256(wheel)},
            "tflite": {
                DETECTOR_IN_WHEEL: sha256(detector),
                LANDMARK_IN_WHEEL: sha256(landmark),
            },
            "onnx": {
                DETECTOR_ONNX: sha256(args.out / DETECTOR_ONNX),
                LANDMARK_ONNX: sha256(args.out / LANDMARK_ONNX),
            },
            "detector_densify_ops_replaced": n_densify,
            "landmark_outputs_kept": LANDMARK_OUTPUTS,
            "opset": OPSET,
            "max_abs_diff_onnx_vs_tflite": {
                "inputs": f"1 uniform random tensor + {len(REAL_PHOTOS)} real photos "
                f"({', '.join(REAL_PHOTOS)}) resized to the model input",
                DETECTOR_ONNX: det_diff,
                LANDMARK_ONNX: lm_diff,
            },
            "tools": {
                "python": platform.python_version(),
                "tensorflow": tf.__version__,
                "tf2onnx": tf2onnx.__version__,
                "onnx": onnx.__version__,
                "onnxruntime": onnxruntime.__version__,
            },
        }
    (args.out / "PROVENANCE.json").write_text(json.dumps(provenance, indent=2) + "\n")
    print(json.dumps(provenance, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
