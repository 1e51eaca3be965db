"""Frame-by-frame BlazePose: detect, track, smooth.

:class:`PoseEstimator` runs MediaPipe 0.10.21's pose pipeline on onnxruntime:

1. With no track, the detector finds people; the kept detection is the one nearest the
   person last tracked (the best-scoring one when there is none), so a second person in view
   does not steal the track when it is re-acquired. When it finds nobody in the whole frame
   (or the landmark model finds no person where it pointed), it looks again in overlapping
   tiles of half the frame's size, then of a quarter (``detect_closer``): a person far from
   the camera is too small for it in the whole frame. A person found only in the tiles of a
   quarter counts when found again in a window of that size centred on them
   (``found_again``): 35 such tiles give noise 35 chances to look like a person. One whose
   hips lie in the ROI of the person tracked on the frame before (``near_track``: the track
   was lost on this frame) needs no second look: it is that person, and a person close to
   the camera, larger than the window, is never found again in it.
2. The landmark model runs on the ROI (from the detection, or from the previous frame's
   auxiliary landmarks when tracking). If its person probability drops below
   ``min_tracking_confidence`` the track is dropped and the detector runs again on the SAME
   frame (MediaPipe waits for the next frame; re-detecting at once loses fewer frames).
3. Smoothing (``smoothing=True``): One Euro filters on image landmarks, world landmarks and
   the ROI's auxiliary landmarks and a low-pass on visibility, with MediaPipe's parameters
   (:mod:`features.pose_estimation.smoothing`). Filters restart after a frame with no person.

World landmarks are returned in the project's canonical frame: MediaPipe's world frame is
x right (image), y down, z away from the camera (right-handed); rotating it by 180 degrees
about x gives x right, y up, z toward the camera: ``canonical = (x, -y, -z)``, still
right-handed (determinant +1), origin at the hip centre, metres.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from . import detector as det
from . import landmarks as lmk
from .model import DETECTOR_PATH, LANDMARK_PATH, make_session
from .smoothing import (
    AUX_FILTER,
    IMAGE_FILTER,
    VISIBILITY_ALPHA,
    WORLD_FILTER,
    LowPassFilter,
    OneEuroFilter,
)

NUM_POSE = lmk.NUM_POSE
# MediaPipe world frame (x right, y down, z away from camera) -> canonical (x right, y up,
# z toward camera): a 180 degree rotation about x.
WORLD_TO_CANONICAL = np.array([1.0, -1.0, -1.0])


@dataclass(frozen=True)
class FramePose:
    """BlazePose result for one frame.

    image: ``(33, 5)`` x px, y px, z px (image-width scale), visibility, presence;
    world: ``(33, 3)`` metres, canonical frame (x right, y up, z toward the camera, origin at
    the hip centre). Both all-NaN when ``person`` is False. ``detected``: the detector ran on
    this frame; ``score``: the landmark model's person probability (NaN if it did not run).
    """

    image: np.ndarray
    world: np.ndarray
    person: bool
    detected: bool
    score: float
    roi: lmk.Roi | None

    @staticmethod
    def missing(detected: bool, score: float = float("nan")) -> FramePose:
        return FramePose(
            image=np.full((NUM_POSE, 5), np.nan),
            world=np.full((NUM_POSE, 3), np.nan),
            person=False,
            detected=detected,
            score=score,
            roi=None,
        )


class EstimatorClosed(Exception):
    """:meth:`PoseEstimator.process` after :meth:`PoseEstimator.close`."""


class PoseEstimator:
    """Stateful BlazePose (full) estimator; feed frames in order with :meth:`process`.

    tracking: reuse the previous frame's landmarks for the ROI (False: detector every frame).
    smoothing: temporal filters (see the module docstring). threads: onnxruntime intra-op
    threads per model (default: up to 2).
    """

    def __init__(
        self,
        *,
        tracking: bool = True,
        smoothing: bool = True,
        min_detection_confidence: float = 0.5,
        min_tracking_confidence: float = 0.5,
        threads: int | None = None,
    ) -> None:
        self.tracking = tracking
        self.smoothing = smoothing
        self.min_detection_confidence = min_detection_confidence
        self.min_tracking_confidence = min_tracking_confidence
        self._detector = make_session(DETECTOR_PATH, threads)
        self._landmarker = make_session(LANDMARK_PATH, threads)
        self._det_in = self._detector.get_inputs()[0].name
        self._det_out = [o.name for o in self._detector.get_outputs()]
        self._lm_in = self._landmarker.get_inputs()[0].name
        # Identity: landmarks, Identity_1: flag, Identity_3: heatmap, Identity_4: world.
        self._lm_out = ["Identity", "Identity_1", "Identity_3", "Identity_4"]
        self._image_filter = OneEuroFilter(IMAGE_FILTER)
        self._world_filter = OneEuroFilter(WORLD_FILTER)
        self._aux_filter = OneEuroFilter(AUX_FILTER)
        self._vis_filter = LowPassFilter(VISIBILITY_ALPHA)
        self._frame = 0
        self._busy = threading.Lock()  # held while process runs the models on a frame
        self._closed = False
        self.reset()

    def reset(self) -> None:
        """Forget the track and the filters (call between unrelated clips)."""
        self._roi: lmk.Roi | None = None
        self._last_centre: np.ndarray | None = None
        self._closer_at: dict[int, float] = {}  # zoom -> the frame time of its last search
        self._finer_next = 0  # the next finer tile of a sweep under way (0: none)
        self._reset_filters()

    def _reset_filters(self) -> None:
        for f in (self._image_filter, self._world_filter, self._aux_filter, self._vis_filter):
            f.reset()

    def detect(self, rgb: np.ndarray) -> list[det.Detection]:
        """All people the detector finds in an RGB uint8 frame ``(h, w, 3)``, best first."""
        tensor, side, off_x, off_y = det.letterbox(rgb)
        outs = self._detector.run(self._det_out, {self._det_in: tensor})
        by_name = dict(zip(self._det_out, outs, strict=True))
        return det.postprocess(
            by_name["Identity"],
            by_name["Identity_1"],
            side,
            off_x,
            off_y,
            self.min_detection_confidence,
        )

    def detect_closer(
        self, rgb: np.ndarray, zoom: int = det.ZOOM, part: slice = slice(None)
    ) -> list[det.Detection]:
        """:meth:`detect` on overlapping tiles of the frame ``zoom`` times smaller than it
        (:func:`.detector.tiles`; ``part``: those of them), each person once, best first: a
        person too small in the whole frame for the detector (far from the camera, or the
        picture small in a large frame) is found in a tile."""
        found: list[det.Detection] = []
        for x, y, w, h in det.tiles(rgb.shape[1], rgb.shape[0], zoom)[part]:
            found += det.shifted(self.detect(rgb[y : y + h, x : x + w]), x, y)
        return det.distinct(found)

    def _due(self, zoom: int, time_s: float, every_s: float) -> bool:
        """Whether the tiles of ``zoom`` are due: not searched in the last ``every_s``
        seconds of frame time (0: always; a frame with no time, NaN, is searched), marked
        searched now when they are."""
        if every_s > 0 and time_s - self._closer_at.get(zoom, -math.inf) < every_s:
            return False
        if math.isfinite(time_s):
            self._closer_at[zoom] = time_s
        return True

    def _searches(
        self,
        rgb: np.ndarray,
        time_s: float,
        every_s: tuple[float, float],
        tiles_per_frame: int | None,
    ) -> Iterator[tuple[bool, list[det.Detection]]]:
        """The detector's finds, search by search, each run only when the one before found
        no person, with whether they come from the finer tiles: the whole frame; the tiles
        of half its size, at most once in ``every_s[0]`` seconds of frame time; those of a
        quarter, a sweep of them begun at most once in ``every_s[1]`` and searched at most
        ``tiles_per_frame`` tiles a frame, those of half counted (None: the whole sweep at
        once), so that no frame waits for more detector runs than the limit: six on every
        frame with nobody in view would leave a camera's frames behind, 28-35 an extract's
        far behind."""
        yield False, self.detect(rgb)
        width, height = rgb.shape[1], rgb.shape[0]
        budget = math.inf if tiles_per_frame is None else tiles_per_frame
        half = det.tiles(width, height)
        if half and self._due(det.ZOOM, time_s, every_s[0]):
            budget -= len(half)
            yield False, self.detect_closer(rgb)
        finer = det.tiles(width, height, det.FINER_ZOOM)
        if not finer or budget < 1:
            return
        if self._finer_next == 0 and not self._due(det.FINER_ZOOM, time_s, every_s[1]):
            return
        start = self._finer_next
        stop = int(min(len(finer), start + budget))
        self._finer_next = stop % len(finer)
        yield True, self.detect_closer(rgb, det.FINER_ZOOM, slice(start, stop))

    def found_again(self, rgb: np.ndarray, found: det.Detection) -> bool:
        """Whether a person found in a finer tile is found again at a second look: the
        detector on a window of the finer tiles' size centred on the find's hip point finds
        the same person (:func:`.detector.same_person`) and the landmark model sees a person
        there (its probability at least ``min_tracking_confidence``). The finer tiles look
        at 35 windows of a 4:3 frame where the whole frame and the tiles of half look at 7,
        each a chance for a pattern to look like a person to one look; a person stays a
        person when the window moves, a pattern in noise seldom does."""
        width, height = rgb.shape[1], rgb.shape[0]
        x, y, side = det.window_around(width, height, found.keypoints[0], det.FINER_ZOOM)
        seen = det.shifted(self.detect(rgb[y : y + side, x : x + side]), x, y)
        for again in det.same_person(found, seen):
            roi = lmk.roi_from_points(again.keypoints[0], again.keypoints[1])
            if self.landmarks(rgb, roi).flag >= self.min_tracking_confidence:
                return True
        return False

    def near_track(self, found: det.Detection) -> bool:
        """Whether ``found``'s hip point lies within the ROI of the person tracked on the
        frame before (within half its side of its centre, the tracked hips), the track lost
        on this frame: that person found again, wherever the tiles found them. A person
        close to the camera is larger than a finer tile: the detector's box (the face's)
        lies far from the hips it predicts, outside a window of the tile's size centred on
        them, so :meth:`found_again` cannot find them again. False (the second look
        decides) with no track on the frame before."""
        if self._roi is None:
            return False
        at = np.array([self._roi.cx, self._roi.cy])
        return float(np.hypot(*(found.keypoints[0] - at))) <= self._roi.size / 2

    def landmarks(self, rgb: np.ndarray, roi: lmk.Roi) -> lmk.RawLandmarks:
        """The landmark model on ``roi`` of an RGB uint8 frame (no smoothing)."""
        tensor, _ = lmk.crop(rgb, roi)
        outs = self._landmarker.run(self._lm_out, {self._lm_in: tensor})
        return lmk.decode(outs[0], outs[1], outs[2], outs[3], roi)

    def _ordered(self, found: list[det.Detection]) -> list[det.Detection]:
        """``found`` nearest the person last tracked first (best first when there is none)."""
        if self._last_centre is None:
            return found
        at = self._last_centre
        return sorted(found, key=lambda d: float(np.hypot(*(d.keypoints[0] - at))))

    def _find(
        self,
        rgb: np.ndarray,
        time_s: float,
        every_s: tuple[float, float],
        tiles_per_frame: int | None,
        score: float,
    ) -> tuple[lmk.RawLandmarks | None, float]:
        """The person the searches (:meth:`_searches`) find, if any, and the landmark
        model's person probability on the last find looked at (``score`` when none). Of each search
        the find nearest the person last tracked (the best when there is none) is looked
        at; of the finer tiles' search every find in that order until one is the person
        tracked on the frame before (:meth:`near_track`) or found again
        (:meth:`found_again`): a pattern in noise may be surer than a small person
        elsewhere."""
        for finer, found in self._searches(rgb, time_s, every_s, tiles_per_frame):
            for best in self._ordered(found)[: None if finer else 1]:
                raw = self.landmarks(rgb, lmk.roi_from_points(best.keypoints[0], best.keypoints[1]))
                score = raw.flag
                if raw.flag >= self.min_tracking_confidence and (
                    not finer or self.near_track(best) or self.found_again(rgb, best)
                ):
                    return raw, score
        return None, score

    def process(
        self,
        rgb: np.ndarray,
        time_s: float | None = None,
        *,
        closer_every_s: float = 0.0,
        finer_every_s: float = 0.0,
        tiles_per_frame: int | None = None,
    ) -> FramePose:
        """One RGB uint8 frame ``(h, w, 3)`` taken at ``time_s`` seconds (default: 30 fps; NaN:
        a frame with no time, its pose not smoothed and the filters left as they were).
        ``closer_every_s``: with nobody found in the whole frame, the tiles of half its size
        are searched (:meth:`detect_closer`) at most once in that many seconds of frame time
        (0: every such frame); ``finer_every_s``: with nobody found in those either, the tiles
        of a quarter (:data:`.detector.FINER_ZOOM`), searched at most ``tiles_per_frame``
        tiles a frame, both sizes counted (None: all). :class:`EstimatorClosed` once
        :meth:`close` was called."""
        with self._busy:
            if self._closed:
                raise EstimatorClosed("the pose estimator was closed")
            return self._process(rgb, time_s, closer_every_s, finer_every_s, tiles_per_frame)

    def close(self, timeout_s: float) -> None:
        """No frame processed from now on (:meth:`process` raises :class:`EstimatorClosed`),
        the one another thread is processing finished first (waited for up to
        ``timeout_s``): a thread left inside onnxruntime as Python shuts down aborts the
        process ("terminate called without an active exception", exit 134)."""
        got = self._busy.acquire(timeout=timeout_s)
        self._closed = True
        if got:
            self._busy.release()

    def _process(
        self,
        rgb: np.ndarray,
        time_s: float | None,
        closer_every_s: float,
        finer_every_s: float,
        tiles_per_frame: int | None,
    ) -> FramePose:
        """:meth:`process`, the models' lock held."""
        if time_s is None:
            time_s = self._frame / 30.0
        self._frame += 1
        raw: lmk.RawLandmarks | None = None
        score = float("nan")
        if self.tracking and self._roi is not None:
            raw = self.landmarks(rgb, self._roi)
            score = raw.flag
            if raw.flag < self.min_tracking_confidence:
                raw = None
                self._reset_filters()
        detected = raw is None
        if raw is None:
            every = (closer_every_s, finer_every_s)
            raw, score = self._find(rgb, time_s, every, tiles_per_frame, score)
        if raw is None:
            self._roi = None
            self._reset_filters()
            return FramePose.missing(detected, score)

        image = raw.image[:NUM_POSE].copy()
        world = raw.world[:NUM_POSE].copy()
        aux = raw.image[NUM_POSE : NUM_POSE + 2, :3].copy()
        if self.smoothing and math.isfinite(time_s):  # NaN: a frame left out for its time,
            # passed through unsmoothed, the filters untouched
            # Speed is measured in body sizes: the object scale is the unscaled ROI side.
            object_scale = 2.0 * float(np.hypot(*(aux[1, :2] - aux[0, :2])))
            value_scale = 1.0 / object_scale if object_scale > 1e-6 else 1.0
            image[:, 3] = self._vis_filter.apply(image[:, 3])
            image[:, :3] = self._image_filter.apply(time_s, image[:, :3], value_scale)
            world = self._world_filter.apply(time_s, world)
            aux = self._aux_filter.apply(time_s, aux, value_scale)
        roi = lmk.roi_from_points(aux[0, :2], aux[1, :2])
        self._roi = roi if self.tracking else None
        self._last_centre = aux[0, :2].copy()
        return FramePose(
            image=image,
            world=world * WORLD_TO_CANONICAL,
            person=True,
            detected=detected,
            score=score,
            roi=roi,
        )
