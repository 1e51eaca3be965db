"""Make the README's workout video from the real exercise clips in ``../shared/data/videos``.

The later part of four clips (jumping jacks, squats, incline push-ups, glute bridges), one
after the other, is the workout; the earlier part of each clip is the training data, one
folder per exercise. Every part is letterboxed into 960x540 at 25 fps (the 5-fps squat
clip's frames are repeated), so training and workout look alike to the pose model. The case
base has seen these people, other repetitions of theirs: a demonstration, not a measurement.

    python tools/make_workout.py OUT_DIR
    # OUT_DIR/workout.mp4, OUT_DIR/train/<exercise>/<exercise>.mp4, OUT_DIR/workout_truth.csv
    # (label,start_s,end_s a part) and OUT_DIR/workout_labels.txt (the label of every frame
    # of workout.mp4, as ``posecbr segment --truth`` reads a label file)
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import cv2
import numpy as np

from features.errors import DataError
from features.pose_estimation.video import open_video

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data")) / "videos"
SIZE, FPS = (960, 540), 25.0
# clip, label, seconds where the workout part starts (before it: training)
PARTS = (
    ("edge/jumping_jack_two_people_pexels8402086.mp4", "jumping_jack", 5.0),
    ("squat/tfjs_pose_squats_pexels4838220.mp4", "squat", 5.2),
    ("edge/incline_pushup_cropped_pexels6970145.mp4", "incline_pushup", 5.0),
    ("glute_bridge/fit_glute_bridge_pexels6525487.mp4", "glute_bridge", 3.0),
)


def _frames(path: Path) -> tuple[list[np.ndarray], float]:
    cap = cv2.VideoCapture(str(path))
    fps = float(cap.get(cv2.CAP_PROP_FPS))
    frames = []
    while True:
        ok, bgr = cap.read()
        if not ok:
            break
        frames.append(bgr)
    cap.release()
    return frames, fps


def _letterbox(bgr: np.ndarray) -> np.ndarray:
    h, w = bgr.shape[:2]
    if (w, h) == SIZE:  # already the size: resizing to it would give the same pixels
        return bgr
    scale = min(SIZE[0] / w, SIZE[1] / h)
    small = cv2.resize(bgr, (int(w * scale), int(h * scale)), interpolation=cv2.INTER_AREA)
    out = np.zeros((SIZE[1], SIZE[0], 3), dtype=np.uint8)
    y, x = (SIZE[1] - small.shape[0]) // 2, (SIZE[0] - small.shape[1]) // 2
    out[y : y + small.shape[0], x : x + small.shape[1]] = small
    return out


def _write(path: Path, frames: list[np.ndarray], fps: float) -> float:
    """Letterboxed frames at 25 fps; returns the seconds written."""
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), FPS, SIZE)
    repeat = max(1, int(round(FPS / fps)))
    last, boxed = None, None
    for bgr in frames:
        if bgr is not last:  # a frame repeated (the 5-fps squat clip's) is boxed once
            last, boxed = bgr, _letterbox(bgr)
        for _ in range(repeat):
            writer.write(boxed)
    writer.release()
    return len(frames) * repeat / FPS


def _unreadable() -> str | None:
    """The first source clip that is missing or does not decode, said in one line; None when
    every one gives a frame."""
    for name, _, _ in PARTS:
        path = DATA / name
        if not path.is_file():
            return (
                f"{path}: no such file (the clips are read from ../shared/data/videos beside"
                " the repository, or from $POSECBR_SHARED_DATA/videos)"
            )
        try:  # posecbr's own check: one line, FFmpeg's complaints kept off stderr
            open_video(path)[0].release()
        except DataError as exc:
            return str(exc)
    return None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("out", type=Path, help="output folder")
    args = parser.parse_args(argv)
    problem = _unreadable()
    if problem:  # before anything is written: a 0-s workout and empty training videos
        print(f"make_workout.py: error: {problem}", file=sys.stderr)
        return 1
    args.out.mkdir(parents=True, exist_ok=True)
    workout: list[np.ndarray] = []
    truth = ["label,start_s,end_s"]
    per_frame: list[str] = []
    t = 0.0
    for name, label, split_s in PARTS:
        frames, fps = _frames(DATA / name)
        cut = int(round(split_s * fps))
        _write(args.out / "train" / label / f"{label}.mp4", frames[:cut], fps)
        repeat = max(1, int(round(FPS / fps)))
        workout += [f for f in frames[cut:] for _ in range(repeat)]
        seconds = len(frames[cut:]) * repeat / FPS
        truth.append(f"{label},{t:.2f},{t + seconds:.2f}")
        per_frame += [label] * (len(frames[cut:]) * repeat)
        t += seconds
    _write(args.out / "workout.mp4", workout, FPS)
    (args.out / "workout_truth.csv").write_text("\n".join(truth) + "\n", encoding="utf-8")
    (args.out / "workout_labels.txt").write_text("\n".join(per_frame) + "\n", encoding="utf-8")
    print(
        f"wrote {args.out / 'workout.mp4'} ({t:.1f} s), {args.out / 'train'}/, truth CSV"
        " and label file"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
