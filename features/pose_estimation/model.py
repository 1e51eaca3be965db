"""The two BlazePose ONNX models shipped with the package, and onnxruntime sessions for them.

The models are converted offline from the ``mediapipe==0.10.21`` wheel by
``tools/convert_blazepose.py`` (see ``models/PROVENANCE.md``); nothing is downloaded at run time.
"""

from __future__ import annotations

import hashlib
import os
import threading
from functools import lru_cache
from pathlib import Path

import onnxruntime as ort

from features.errors import ConfigError

MODEL_DIR = Path(__file__).resolve().parent / "models"
DETECTOR_PATH = MODEL_DIR / "pose_detection.onnx"
LANDMARK_PATH = MODEL_DIR / "pose_landmark_full.onnx"
# Bump when the pipeline's output changes for the same models (decoding, ROI, smoothing,
# coordinate conversion): pose files made by an older pipeline are then re-extracted.
PIPELINE_VERSION = "1"


@lru_cache(maxsize=1)
def model_version() -> str:
    """``blazepose-full-<12 hex of the models' sha256>-p<pipeline version>``."""
    h = hashlib.sha256()
    for path in (DETECTOR_PATH, LANDMARK_PATH):
        try:
            h.update(path.read_bytes())
        except OSError as exc:
            raise ConfigError(f"BlazePose model missing ({exc.strerror})", path) from None
    return f"blazepose-full-{h.hexdigest()[:12]}-p{PIPELINE_VERSION}"


def default_threads() -> int:
    return max(1, min(2, os.cpu_count() or 1))


def make_session(path: Path, threads: int | None = None) -> ort.InferenceSession:
    """An onnxruntime CPU session for one of the models, made once per process for each
    model and thread count (:data:`_SESSIONS`).

    ``session.intra_op.allow_spinning = "0"``: the detector and landmark sessions alternate on
    the same cores; with spinning threads each session's idle pool burns the cores the other
    one needs (about 40 % less throughput on 2 cores, measured).
    """
    if not path.exists():
        raise ConfigError("BlazePose model missing (reinstall posecbr)", path)
    n = threads or default_threads()
    key = (str(path), n, os.getpid())
    with _SESSIONS_LOCK:
        if key not in _SESSIONS:
            _SESSIONS[key] = _new_session(path, n)
        return _SESSIONS[key]


_SESSIONS: dict[tuple[str, int, int], ort.InferenceSession] = {}
"""The sessions made so far. A session holds no state between runs (the estimator's track and
filters are its own) and onnxruntime runs one from several threads at once, so every
:class:`~features.pose_estimation.PoseEstimator` of a process shares them: before, each video
of a training folder (``posecbr train VIDEOS``, one estimator per video) loaded and optimised
both models again, 0.05 s of CPU and 0.1-0.6 s of wall time a video at load 7-8. Keyed by
the process too: a forked worker (``extract --workers``) makes its own, as a session's
thread pool does not survive a fork."""
_SESSIONS_LOCK = threading.Lock()


def _new_session(path: Path, threads: int) -> ort.InferenceSession:
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = threads
    opts.inter_op_num_threads = 1
    opts.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    opts.add_session_config_entry("session.intra_op.allow_spinning", "0")
    opts.log_severity_level = 3
    return ort.InferenceSession(str(path), sess_options=opts, providers=["CPUExecutionProvider"])
