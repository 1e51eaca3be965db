"""Write MediaPipe 0.10.21 ``solutions.pose`` landmarks for still images as a JSON reference.

Runs in a separate virtual environment that has MediaPipe (never the project's)::

    python3.11 -m venv /work/mp-venv
    /work/mp-venv/bin/pip install --no-deps mediapipe==0.10.21
    /work/mp-venv/bin/pip install absl-py attrs flatbuffers 'protobuf<5' matplotlib \
        numpy opencv-python-headless
    /work/mp-venv/bin/python tools/make_mediapipe_reference.py \
        ../shared/data/media/basketball1.png ... --out tests/fixtures/mediapipe_pose_reference.json

Settings: ``static_image_mode=True`` (detector on every image, no smoothing),
``model_complexity=1`` (the full landmark model, the one converted to ONNX),
``min_detection_confidence=0.5``. Image landmarks are stored in pixels (x, y), z in pixels at
the image width's scale (MediaPipe's normalised z times the width) and visibility (the
Python solution leaves presence unset, so none is stored);
world landmarks in MediaPipe's own frame (metres; x right, y down, z away from the camera,
origin at the hip centre).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import cv2
import mediapipe as mp
import numpy as np


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("images", nargs="+", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    result: dict[str, object] = {
        "generator": "tools/make_mediapipe_reference.py",
        "mediapipe": mp.__version__,
        "settings": {
            "static_image_mode": True,
            "model_complexity": 1,
            "min_detection_confidence": 0.5,
            "smooth_landmarks": False,
        },
        "images": {},
    }
    images: dict[str, object] = {}
    with mp.solutions.pose.Pose(
        static_image_mode=True, model_complexity=1, min_detection_confidence=0.5
    ) as pose:
        for path in args.images:
            bgr = cv2.imread(str(path))
            if bgr is None:
                raise SystemExit(f"{path}: cannot read image")
            h, w = bgr.shape[:2]
            out = pose.process(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))
            entry: dict[str, object] = {
                "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
                "width": w,
                "height": h,
                "person": out.pose_landmarks is not None,
            }
            if out.pose_landmarks is not None:
                lm = np.array(
                    [[p.x * w, p.y * h, p.z * w, p.visibility] for p in out.pose_landmarks.landmark]
                )
                world = np.array([[p.x, p.y, p.z] for p in out.pose_world_landmarks.landmark])
                entry["image_landmarks_px"] = np.round(lm, 5).tolist()
                entry["world_landmarks_m"] = np.round(world, 6).tolist()
            images[path.name] = entry
    result["images"] = images
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
