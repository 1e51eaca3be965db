"""Repetitions: how many times a movement is repeated in a clip, and where each one starts and
ends, from the joint angles (:func:`features.derived.signals_of`).

What counts as one repetition (the way people count exercises):

- one excursion from the rest posture to the far point of the movement and back (a squat:
  standing, down, standing); a repetition cut off by the clip's start or end counts when its
  far point is in the clip and reaches (nearly) as far as the whole ones, and a clip with no
  whole repetition (only the way down of a squat) has none (:func:`_whole_only`);
- a movement that alternates sides (left knee up, then right knee up; twist right, then left;
  jogging steps) has one repetition per side.

How (all channels at once, no per-frame loops):

1. the angles of :data:`COUNTED_ANGLES` (with the forearms' direction across the upper arms,
   :func:`upper_arm_turn`, for a turn of the upper arm about its own axis, and the hips' height
   above the floor in trunk lengths, :func:`pelvis_height`, for the whole body going up and
   down), missing where the
   camera does not see their joints,
   gaps interpolated, cleaned of tracking glitches (those of a few frames that jump away
   and back, :func:`_drop_glitches`; then a running median, :data:`MEDIAN_S`),
   smoothed (Gaussian, :data:`SMOOTHING_S`) and analysed at about :data:`ANALYSIS_FPS`; a
   far point (step 5) in a stretch of at least :data:`MIN_PERIOD_S` in which no frame shows
   the person lies where the person was last or next seen (the values there are filled in: a
   posture held is a plateau, whose middle is no far point);
2. the period T (:func:`find_period`): the first strong peak of the summed autocorrelation of
   the angle velocities (velocities, so that a one-off change of posture does not hide the
   repetitions), each lag's estimate weighted by its overlap with the clip (the biased
   estimator: a lag near the clip's length rests on few samples and must not pass for the
   period by noise); a left-right alternation repeats after a full cycle, so T is the full
   cycle;
3. alternation (:func:`side_parts`): the deviations from the left-right symmetric mean
   posture split into what both sides do alike and what one side does against the other
   (:func:`mirror_angles`); the movement alternates when the second spans at least half as
   much as the first (an angle whose twin's joint is never seen is not shown to move against
   it, and counts with the first), the left and the right limbs move about equally (within
   a factor of two: a one-legged kick does not alternate), in all and in the limbs that
   carry the side-against-side movement (a kick whose arms swing to balance neither),
   compared only where both sides are seen (:func:`_twinned`; with no limb seen on both
   sides the movement is not taken to alternate), the body goes
   out to both sides about equally far, and what one side does at its far points is the
   other's movement mirrored
   (:data:`ALTERNATION_MIN`: a kick answered by the other arm's swing is not) (the spans and
   the mirroring taken about their running mean over one period, however clearly the
   side-against-side movement repeats, as long as it repeats more than noise would:
   bending the arms once to start jogging, or the end of the exercise before it in a
   stretch cut a little early, is not what repeats; and the far
   points' postures opposed about the symmetric posture as well, as recorded: about its
   running mean a one-arm raise is opposed to itself);
4. the movement as one number per sample: the posture projected on the direction it moves
   back and forth along most (:func:`movement_direction`; each angle weighted by its
   periodic energy, :func:`periodic_share`, so that jitter and one-off changes do not pull
   it, and the period read again so weighted), signed so that it rises away from rest (the
   end whose trunk tilts less far head-down past the horizontal when the ends differ in it:
   hips held up above the shoulders, a bridge lying on the back, are no rest; otherwise the
   end nearer standing at ease, :data:`AT_EASE`, when the angles that have an at-ease value
   carry the movement; where they do not, a shoulder turning in and out, or the two ends lie
   about equally far from ease, the end the clip's first and last moments lie nearer,
   :data:`ENDS_S`; each end the line's outer tenth of the frames, or of its range where a
   clip mostly at rest has fewer frames there) and, for a clearly periodic
   movement, taken about its running mean over one period; for an alternating movement, the
   side-against-side part, whose peaks are one side's repetitions and troughs the other's,
   read along the angles that go out and come back rather than those held off to one side
   when the body moves along them as far (:func:`_side_direction`)
   (small wobbles about the symmetric posture between them are none, :func:`_taking_turns`;
   two of one side that the whole posture does not come back toward rest between are one,
   :func:`_one_side_out`; one cut off by the clip's start or end counts when it got nearly
   as far as the whole repetitions left, not the wobbles);
5. repetitions are the peaks that stand out by at least :data:`SUBSTANTIAL` of the typical
   repetition and by :data:`MIN_EXCURSION_RAD` (more than pose-estimation jitter), from which
   the movement falls back by :data:`RETURN_SHARE` of their height above rest on both sides
   (a far point reached again after a shallow dip is the same repetition; rest is the
   lowest of the line around the far point, from the far points next to it and within a
   period of it, :func:`_floors`, not of the whole clip: small arm circles held high keep
   their count once wide ones reach lower; two far points between which the line as
   recorded does not come back toward rest by :data:`HOLD_SHARE` of their height are one,
   :func:`_one_hold`: a squat held at the bottom longer than the period; so are two between
   which the whole posture does not come back toward rest by that share of the way it went
   out to either, :func:`_posture_stays_out`: a front kick's two knee bends, the hip raised
   between them), that rise above
   the lowest of the line as recorded within a period of them by :data:`STILL_SHARE` of
   the typical rise (the middle of a long rest between repetitions does not), at least
   half a period apart when the movement repeats clearly (:data:`CLEAR_PERIODICITY`; a
   period read from a weak autocorrelation is often a multiple of the true one, and would
   merge repetitions); each runs from the low point between it and the one before to the
   low point between it and the one after (the spans follow one another); the first starts
   where the movement leaves rest and the last ends where it returns to rest: where the
   line lies within :data:`LEAVE_SHARE` of the peak's height above the low point before the
   first peak and after the last (a lone repetition between two rests, whose flat, noisy
   low point lies anywhere in the rest, does not take the rest in), the low point sought
   within a period of the peak, or, for the one repetition of a whole recording, anywhere
   in it (one far point repeats nothing: a period read from a wobble or a pose model's
   left-right flicker, 0.44 s in a 10-s video of one slow lunge, cut its repetition to the
   0.52 s around the flicker, though the lunge went on down and up for 5 s). A recording with one
   far point that starts at one end of the movement and ends at the other, held still
   there, got into a posture once (a side plank) and has none (:func:`_held_change`).

The period also comes out of the QMP fits (:mod:`features.qmp`: SINDy with a period per state
signal); the autocorrelation is used here because it reads all angles together and needs no
window length, and the tests check that both agree.

Cases for a case base: :func:`split_repetitions` cuts clips into their repetitions (a jog's
steps, too short alone, into whole left-and-right cycles, :func:`case_spans`),
:func:`split_windows` into the fixed windows ``posecbr segment`` classifies.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .blas import one_blas_thread
from .body import check_person, long_runs
from .datasets import Clip
from .derived import signals_of, stretch
from .errors import DataError
from .geometry import WORLD_UP, angle_between, body_frame, joint_angle, unit
from .jitter import MAD_TO_SD
from .leg_swaps import SWAP_JOINTS, swapped_legs
from .nanstats import over_seen
from .poses import PoseSequence, expect_sequence
from .signals import ANGLE_SIGNALS
from .skeleton import JOINT_INDEX

ANALYSIS_FPS = 30.0
"""Signals are analysed at about this rate: repetitions last 0.3 s or more."""
SMOOTHING_S = 0.08
"""Gaussian smoothing (sigma, seconds): removes tracking jitter, keeps movements of 0.3 s+."""
MIN_PERIOD_S = 0.4
"""No exercise repeats faster than this (jogging steps take about 0.3-0.4 s per side)."""
MIN_EXCURSION_RAD = float(np.radians(15.0))
"""A repetition moves the body at least this far in joint-angle space (radians); pose
estimation from video jitters single joints by a few degrees, postural sway by less."""
MIN_VALID_SHARE = 0.5
"""An angle missing in more than half of the frames that show the person does not take part
(frames in which nobody is seen do not count against it: a recording the person leaves for
most of its time is followed while they are there). A frame in a gap of at most
:data:`MAX_FILLED_GAP_S` counts as there: the angle is filled in it between its values either
side."""
MAX_FILLED_GAP_S = 0.1
"""An angle missing for this long or less (a joint the pose model dropped for a frame or two,
however often) is filled between its values either side, as finely as the running median
(:data:`MEDIAN_S`) already reads it, and counts as followed there. Before, an angle had to be
seen itself in half of the frames: with a third of the joints dropped at random in each
frame, only the hips' height took part and a recording's jumping jacks, twists, knee raises
and arm circles counted none."""
ALTERNATION_MIN = 0.5
"""A movement alternates sides (one repetition per side) only when what one side does at its
far points and what the other does at its own are opposed by more than this cosine
(:func:`_sides_mirror`): the same movement, once on each side."""

_LATERAL = {"neck_frontal", "torso_frontal", "neck_transverse", "torso_transverse"}

TRUNK_SIDE_SHARE = 0.2
"""An alternating movement whose trunk's sideways lean and twist carry at least this share of
its side-against-side direction (squared weights) takes its sides from the trunk: the way the
shoulders turn or the trunk leans, as the fluents "torso twisted left" and "torso tilted left"
read it (a twist, the arms turning with it; the limbs alone would name a side by which arm
turns farther). A twist's trunk carries well above this share, knee raises and jogging well
below (docs/measurements.md, "Figures behind the code's rules: Counting repetitions")."""

PELVIS_HEIGHT = "pelvis_height"
"""The hip centre's height above the floor, in trunk lengths (:func:`pelvis_height`)."""
TWIST_NAMES: tuple[str, ...] = ("left_upper_arm_turn", "right_upper_arm_turn")
"""The forearms' sideways direction across the upper arms (:func:`upper_arm_turn`): how far the
upper arm has turned about its own axis with the elbow bent."""
LIMB_LINES: dict[str, tuple[str, tuple[str, str, str]]] = {
    **{
        f"{s}_arm_line": (f"{s}_armpit", (f"{s}_wrist", f"{s}_shoulder", f"{s}_hip"))
        for s in ("left", "right")
    },
    **{
        f"{s}_leg_line": (f"{s}_hip", (f"{s}_ankle", f"{s}_hip", f"{s}_shoulder"))
        for s in ("left", "right")
    },
}
"""A limb's line from its root to its end, as the angle at the root between it and the trunk
(the points of :func:`features.geometry.joint_angle`), and the angle it stands in for: the
armpit's read through the wrist, the hip's through the ankle. With the limb's middle joint
(the elbow, the knee) missing, the angles that rest on it take no part and the limb's
movement was read nowhere, though its root and end are seen: a one-arm abduction with that
arm's elbow missing counted 0. A line takes part where the angle it stands in for does not
(:data:`MIN_VALID_SHARE`) and the line does; the other side's does not, its own angles being
read, so the line has no twin and takes no part in comparing the sides (:func:`_twinned`:
with both legs' lines compared, a side view's reverse lunge with a knee missing was taken for
alternating on its trunk's wobble again, 5 repetitions for 1). The line folds the middle
joint's bend and the limb's turn about its own axis into one direction, and so has no end
nearer ease (:func:`_rest_is_high`; read with one, shoulder rotations with the elbow missing
counted their rest plateaus too). A knee missing is placed
where its hip and ankle fix it (:func:`_placed_knees`) and the leg's own angles are read:
its line is read only when no knee is seen to measure the thigh and shank by."""
ARM_RAISES: dict[str, tuple[str, tuple[str, str]]] = {
    f"{s}_arm_raise": (f"{s}_armpit", (f"{s}_shoulder", f"{s}_elbow")) for s in ("left", "right")
}
"""An upper arm's angle from straight down (the world's vertical, as the trunk's inclination
reads it), and the armpit angle it stands in for, from the shoulder and the elbow: with the
hips out of view (a patient filmed close up or seated, the camera upright) the armpit angle
has no trunk to be read against, and an arm raised sideways or forwards with a straight elbow
moved in no angle that was read; such a clip was refused as showing no person. It takes part
as a :data:`LIMB_LINES` line does: where the armpit angle does not and it does
(:func:`_idle_lines`), so a clip that shows the hips is read as before. Standing or sitting
upright, it is the armpit angle; at ease the arm hangs straight down (0)."""
STAND_INS: dict[str, str] = {
    **{n: angle for n, (angle, _) in LIMB_LINES.items()},
    **{n: angle for n, (angle, _) in ARM_RAISES.items()},
}
"""Each angle read only where the one it stands in for is not (:data:`LIMB_LINES`,
:data:`ARM_RAISES`), and that angle."""
COUNTED_ANGLES: tuple[str, ...] = (
    tuple(
        f"{side}_{joint}"
        for joint in ("elbow", "knee", "armpit", "hip")
        for side in ("left", "right")
    )
    + ("trunk_inclination", "torso_sagittal", "torso_frontal", "torso_transverse")
    + TWIST_NAMES
    + (PELVIS_HEIGHT,)
    + tuple(LIMB_LINES)
    + tuple(ARM_RAISES)
)
"""The angles repetitions are read from: the eight limb joint angles (defined in every
posture), the trunk's inclination from the vertical, and its bend, side bend and twist, and
the forearms' sideways direction across the upper arms (:func:`upper_arm_turn`: the turn of the
upper arm about its own axis, shoulder internal and external rotation, which no joint angle
sees), and the hips' height above the floor in trunk lengths (:func:`pelvis_height`: the
whole body going up and down, a hop with still arms and straight legs), and, for a limb whose
middle joint is missing, its line from root to end (:data:`LIMB_LINES`), and, for an arm
whose hips are out of view, its angle from straight down (:data:`ARM_RAISES`). The limb plane angles
are left out: a limb's projection on a plane it is nearly
perpendicular to has no stable direction. The shank across the thigh (the thigh's turn) was
tried and left out: it did no better on the repetition benchmark's training subjects
(``python -m benchmarks.repetitions``)."""
TWIST_SINGULAR_COS = float(np.cos(np.radians(30.0)))
"""The frame attached to the upper arm is swung there from hanging straight down along the
trunk; it has no stable orientation when the arm points within 30 degrees of straight up
along the trunk (the swing's singular direction), where :func:`upper_arm_turn` is missing."""
CLEAR_PERIODICITY = 0.5
"""A movement repeats clearly when the autocorrelation of its velocities at the period is at
least this: most of the movement recurs."""
TRUNK_LEVEL_RAD = float(np.radians(60.0))
"""The trunk's bend, side bend and twist are measured in the body's heading against gravity;
when the trunk lies more than this far from the vertical (lying down, a deep bend) they have no
stable value and count as missing (its inclination still counts)."""
MEDIAN_S = 0.2
"""Running median (seconds) before smoothing (after :func:`_drop_glitches`, which puts back
longer ones that jump): drops tracking glitches shorter than 0.1 s (at
the clip's start and end, where its window is cut to the clip's frames, :func:`_running_median`,
shorter ones)."""
JUMP_SHARE = 0.75
"""A pose model's glitch that outlasts the running median (:func:`_drop_glitches`) jumps
away from the posture around it and back, each jump (from one sample to the next) carrying
at least this share of its farthest: a movement gets there over several samples (a hurdle
step's knee straightens by 30 degrees a frame; with half, a quick repetition's jump was taken
for a glitch and a count came out one too many: docs/measurements.md, "Figures behind the code's
rules: Counting repetitions")."""
MAX_FILTER_FPS = 240.0
"""Above this frame rate the running median and the smoothing read every few frames, at
240-480 fps: the median costs its width at every frame read, and 5 s at 4800 fps (a width
of 961 frames) took 29 s of the count, 10,000 fps a minute at 120 fps' cost times 80."""
SUBSTANTIAL = 0.3
"""A far point counts when it stands out by at least this share of the median prominence of
the candidates (a shallow repetition among deep ones still counts) and falls back by
:data:`RETURN_SHARE` of its height on both sides: chosen together on joined single
repetitions of the repetition benchmark's training subjects only (``python -m
benchmarks.repetitions``), never on its held-out subjects or any other recording
(docs/measurements.md, "Figures behind the code's rules: Counting repetitions")."""
RETURN_SHARE = 0.4
"""A far point counts only when the movement falls back from it, toward the far points
before and after it, by at least this share of its height above rest (its prominence over
its height): a second far point reached after a shallow dip (a wobble at the bottom of a
lunge, a pause on the way up) is part of the same repetition. Rest is the lowest of the
line from the far point before to the far point after, and within a period (:func:`_floors`;
the clip's rest level, its lowest 5 %, when lower): before, the whole clip's rest, which a
small swing held high (a recording's first, small arm circles) stood far above once wide
swings reached lower; they were dropped, and a count went down as the clip grew. Chosen with
:data:`SUBSTANTIAL` on the training subjects only (docs/measurements.md, "Figures behind the
code's rules: Counting repetitions")."""
STILL_SHARE = 0.1
"""A far point is a still stretch, not a repetition, when the movement line as recorded (not
about its running mean) rises less than this share of the median far point's rise above the
lowest of the line within a period of it: the middle of a long rest between repetitions rises
by nothing but noise. Far below :data:`SUBSTANTIAL`: a shallow repetition among deep ones
rises little (the shallowest of the repetition benchmark's training repetitions rose less
than 0.3 of the median and was dropped at 0.3: docs/measurements.md, "Figures behind the code's
rules: Counting repetitions")."""

HOLD_SHARE = RETURN_SHARE
"""Two neighbouring far points are one (:func:`_one_hold`) when the movement as recorded
does not come back toward rest between them by this share of their rise: the return rule
of :data:`RETURN_SHARE`, on the line as recorded; or when the posture does not come back
by this share of the way it went out to either (:func:`_posture_stays_out`): the line is
one direction of the posture, and a dip along it while the rest of the body stays out is no
return. The posture is the counted angles each weighted by its part in the direction the
body moves back and forth along most, unweighted by periodic energy
(:func:`movement_direction`): the kick's hip, which the line's periodic weighting can leave
out, takes part; an arm held otherwise from one take to the next (a change made once)
does not."""

LEAVE_SHARE = 0.1
"""The first repetition starts at the last sample before its peak, and the last ends at the
first sample after its peak, at which the movement line lies within this share of the peak's
height above the low point (before the first peak, after the last): where the movement leaves
and returns to rest, not at the low point itself, which in a flat, noisy rest lies anywhere
in it (single repetitions with some standing at each end started at their clip's first
frame and ended at its last). Chosen on the repetition benchmark's training subjects only
(``python -m benchmarks.repetitions``), on their joined repetitions: the same rule applied on
both sides of each cut between two takes crossed the cut, made in the standing between the
takes, less often the larger the share, steeply up to 0.1 and little after; 0.1 is past the
knee and keeps the most of the movement (of a lone sin-squared excursion it leaves out a
tenth of its time at each end). Never chosen on the held-out subjects or any other
recording (docs/measurements.md, "Figures behind the code's rules: Counting repetitions")."""

EASE_SHARE = 0.5
"""The posture at ease tells which end of a movement is rest only when the angles that have
an at-ease value (:data:`AT_EASE`) carry at least this share of the movement direction's
squared weight."""
TURNED_SHARE = 0.5
"""A far point cut off by the clip's start or end counts beside whole ones when it got three
quarters as far as they did; once the line has turned at it within the clip (falling back
from it, but by less than :data:`MIN_EXCURSION_RAD`: still cut off), when it got this share
as far. A far point's measured height wavers by a few hundredths from one end of the clip to
the next, so one reached at three quarters as the line got there (counted) came out a hair
short as the line turned back from it 0.25 s later (not counted) and was whole 0.25 s after
that (counted): a count going 2, 3, 2, 3 as the clip grew. A far point the line has turned
at is as far as it will get, and half as far as the whole ones leaves the waver no hold. On
the joined recordings of the repetition benchmark's training subjects (``python -m
benchmarks.repetition_growth``, their rows only; with the running median cut at the clip's
ends, :func:`_running_median`) the count went down at fewer 0.25-s steps with a half than
with three quarters, the two values tried; never chosen on the held-out subjects or any
other recording (docs/measurements.md, "Figures behind the code's rules: Counting repetitions")."""
ENDS_S = MIN_PERIOD_S / 2
"""Otherwise the rest end is the one the clip's first and last this many seconds lie nearer
(0.2 s: half the shortest repetition, so the ends do not reach into its far point, as 5 % of
a clip of ten repetitions does)."""

AT_EASE: dict[str, float] = {
    **{f"{s}_{j}": np.pi for s in ("left", "right") for j in ("elbow", "knee", "hip")},
    **{f"{s}_armpit": 0.0 for s in ("left", "right")},
    "trunk_inclination": 0.0,
    **{name: np.pi / 2 for name in ANGLE_SIGNALS if "sagittal" in name or "frontal" in name},
    **{name: np.pi / 2 for name in ANGLE_SIGNALS if "transverse" in name},
    **{name: 0.0 for name in TWIST_NAMES},
    **{name: 0.0 for name in ARM_RAISES},
}
"""Joint angles (radians) of a person standing at ease: elbows, knees and hips straight, arms
down, head and trunk upright and facing forward. The rest end of a movement is the one nearer
this posture, unless one end's trunk tilts farther head-down past the horizontal (the hips
held up above the shoulders: a bridge lying on the back, whose straightened hips lie nearer
this posture than lying flat does)."""


@dataclass(frozen=True)
class Repetition:
    """One repetition: frames ``start_frame`` to ``end_frame`` (exclusive), its far point at
    ``peak_frame``; ``side`` ("left"/"right") for a movement that alternates sides."""

    start_frame: int
    end_frame: int
    peak_frame: int
    side: str | None = None
    held: tuple[bool, bool] = dataclasses.field(default=(False, False), compare=False)
    """Whether the movement as recorded rises to the far point by less than
    :data:`MIN_EXCURSION_RAD` from the clip's start, and falls back from it by less than that
    to the clip's end: the far point is held (or still being reached) up to the clip's start
    or end, however far from it the peak sample lies in a still hold (found by the count of
    one movement, not of an alternating one). A piece of a longer recording beyond such an end
    holds the same far point (:func:`cbr.segmentation.counted_segments`)."""
    unreturned: tuple[bool, bool] = dataclasses.field(default=(False, False), compare=False)
    """Whether the movement as recorded rises to the far point from the clip's start, and
    falls back from it to the clip's end, by less than :data:`RETURN_SHARE` of the far
    point's height (at least :data:`MIN_EXCURSION_RAD`; as :attr:`held`, otherwise): the
    repetition has not come back to rest by that end, as the return rule of :func:`_far_points`
    asks. Two such ends facing one another across a cut, each with a far point of its own
    (a squat held at the bottom that rises a little before the cut and sinks again after
    it), are one repetition (:func:`cbr.segmentation.counted_segments`)."""

    def to_dict(self, fps: float) -> dict[str, Any]:
        return {
            "start_frame": self.start_frame,
            "end_frame": self.end_frame,
            "start_s": round(self.start_frame / fps, 3),
            "end_s": round(self.end_frame / fps, 3),
            "peak_frame": self.peak_frame,
            "side": self.side,
        }


@dataclass(frozen=True)
class RepetitionCount:
    """The repetitions of a clip.

    period_s: the movement's full cycle (None when it does not repeat); periodicity: the
    autocorrelation at that period (1 = exact repetition); ``to_dict`` gives both as None
    without a period or with fewer than two repetitions counted (:attr:`repeated_period_s`);
    alternating: one repetition per side; moving: the joint angles (or the hips' height) that
    carry the movement, most first; partial: no repetition is whole, but the movement reached a
    far point cut off by the clip's start or end (part of one repetition: the way down of a
    squat), which does not count (:func:`_whole_only`).
    """

    repetitions: tuple[Repetition, ...]
    fps: float
    n_frames: int
    period_s: float | None
    periodicity: float
    alternating: bool
    moving: tuple[str, ...]
    partial: bool = False

    @property
    def count(self) -> int:
        return len(self.repetitions)

    @property
    def repeated_period_s(self) -> float | None:
        """The period to tell a user: ``period_s`` when at least two repetitions were
        counted, else None (a period read from a wobble or the pose model's jitter in a
        posture held is not the period of anything repeated: ``reps`` said "0 repetitions
        (period 0.40 s)"; nor is one beside a lone repetition, which repeats nothing: a slow
        lunge, one repetition of 6 s, was given the period of its wobble)."""
        return self.period_s if self.count >= 2 else None

    def to_dict(self) -> dict[str, Any]:
        period = self.repeated_period_s
        return {
            "count": self.count,
            "repetitions": [r.to_dict(self.fps) for r in self.repetitions],
            "period_s": None if period is None else round(period, 3),
            # at no period (nothing repeats) there is no autocorrelation to give: null, not 0
            "periodicity": None if period is None else round(self.periodicity, 3),
            "alternating": self.alternating,
            "moving": list(self.moving),
            "partial": self.partial,
        }


def mirror_angles(values: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """The angles of the left-right mirror image of a posture, ``(frames, len(names))``: every
    left angle takes its right twin's value, and the sideways tilts and turns of head and
    trunk (90 degrees = straight) are reflected about 90 degrees."""
    index = {n: i for i, n in enumerate(names)}
    twin = [index.get(_swap(n), i) for i, n in enumerate(names)]
    out = values[:, twin].copy()
    lateral = [i for i, n in enumerate(names) if n in _LATERAL]
    out[:, lateral] = np.pi - out[:, lateral]
    return out


def _swap(name: str) -> str:
    if name.startswith("left_"):
        return "right_" + name[5:]
    if name.startswith("right_"):
        return "left_" + name[6:]
    return name


@dataclass(frozen=True)
class MovementSignals:
    """Smoothed joint angles at the analysis rate: values ``(n, channels)`` radians, channel
    names, the analysis rate and the source frames per analysis sample (``step``)."""

    values: np.ndarray
    names: tuple[str, ...]
    fps: float
    step: int
    # (n,) True in a stretch of at least MIN_PERIOD_S in which no frame shows the person (the
    # values there are filled in, not measured); None: none such
    blind: np.ndarray | None = None
    # (n, channels) of the ``step`` frames of each sample, in how many each angle was
    # followed (seen, or in a gap short enough to fill: _followed); (n,) in how many any
    # counted angle was seen (the person shown); None: followed wherever shown
    followed: np.ndarray | None = None
    shown: np.ndarray | None = None

    def part(self, a: int, b: int) -> MovementSignals:
        """Samples [a, b) of these signals."""
        return dataclasses.replace(
            self,
            values=self.values[a:b],
            blind=None if self.blind is None else self.blind[a:b],
            followed=None if self.followed is None else self.followed[a:b],
            shown=None if self.shown is None else self.shown[a:b],
        )

    def alone(self, a: int, b: int) -> MovementSignals | None:
        """Samples [a, b) of these signals with the angles a clip of their frames alone would
        count (:func:`movement_signals`): an angle followed in fewer than
        :data:`MIN_VALID_SHARE` of the frames there that show the person is left out (and
        with it, :func:`_twinned`, its twin from comparing the sides); None when none is
        left. The signals of a whole recording keep an angle its joint is seen for in most
        of the recording, filled in across a stretch where it is missing throughout: a piece
        of that stretch read it as a limb held still."""
        part = self.part(a, b)
        if part.followed is None or part.shown is None:
            return part
        keep = _kept(part.followed.sum(axis=0), int(part.shown.sum()))
        if not keep.any():
            return None
        if keep.all():
            return part
        return dataclasses.replace(
            part,
            values=part.values[:, keep],
            names=tuple(n for n, k in zip(part.names, keep, strict=True) if k),
            followed=part.followed[:, keep],
        )


def _kept(there: np.ndarray, shown: int) -> np.ndarray:
    """``(channels,)`` whether each angle, followed in ``there`` ``(channels,)`` frames of
    the ``shown`` that show the person, takes part: followed somewhere, and in at least
    :data:`MIN_VALID_SHARE` of those."""
    return np.asarray((there > 0) & (there >= MIN_VALID_SHARE * shown))


def counted_angles(seq: PoseSequence) -> np.ndarray:
    """The :data:`COUNTED_ANGLES` of ``seq`` (positions ``(frames, joints, 3)``), radians,
    ``(frames, len(COUNTED_ANGLES))``; NaN where undefined: the trunk's bend, side bend and
    twist while it lies far from the vertical, angles on joints the camera does not see, and
    angles on the legs and hips where the pose model swapped the legs
    (:func:`features.leg_swaps.swapped_legs`), and the :data:`LIMB_LINES` that stand in for no
    angle (:func:`_idle_lines`). A knee missing is placed from its hip and ankle first
    (:func:`_placed_knees`)."""
    canonical = seq.to_canonical()
    placed = _placed_knees(canonical)
    sig = signals_of(seq if placed is canonical else placed)  # cached for the clip as it is
    canonical = placed
    p = canonical.positions
    neck = 0.5 * (p[:, JOINT_INDEX["left_shoulder"]] + p[:, JOINT_INDEX["right_shoulder"]])
    mid_hip = 0.5 * (p[:, JOINT_INDEX["left_hip"]] + p[:, JOINT_INDEX["right_hip"]])
    trunk = neck - mid_hip
    inclination = angle_between(trunk, np.broadcast_to(WORLD_UP, trunk.shape))
    extra = {
        **dict(zip(TWIST_NAMES, upper_arm_turn(p).T, strict=True)),
        "trunk_inclination": inclination,
        PELVIS_HEIGHT: pelvis_height(p),
        **{
            n: joint_angle(*(p[:, JOINT_INDEX[j]] for j in js)) for n, (_, js) in LIMB_LINES.items()
        },
        **{n: _from_down(p, *js) for n, (_, js) in ARM_RAISES.items()},
    }
    raw = np.stack([extra[n] if n in extra else sig.column(n) for n in COUNTED_ANGLES], axis=1)
    with np.errstate(invalid="ignore"):
        lying = ~(inclination <= TRUNK_LEVEL_RAD)
    torso = np.array([n.startswith("torso_") for n in COUNTED_ANGLES])
    raw[lying[:, None] & torso[None, :]] = np.nan
    if canonical.confidence is not None:
        raw[_unseen(canonical.confidence)] = np.nan
    swapped = swapped_legs(p, seq.fps, MIN_EXCURSION_RAD, MIN_PERIOD_S, MEDIAN_S)
    raw[swapped[:, None] & _ON_LEGS[None, :]] = np.nan
    raw[:, _idle_lines(np.isfinite(raw), seq.fps)] = np.nan
    return raw


_LEG = {
    s: tuple(JOINT_INDEX[f"{s}_{j}"] for j in ("hip", "knee", "ankle")) for s in ("left", "right")
}


def _placed_knees(canonical: PoseSequence) -> PoseSequence:
    """``canonical`` (on the canonical skeleton) with each knee missing where its hip and
    ankle are there put where the knee's hinge puts it, seen as far as the smaller of the hip's
    and the ankle's confidence, and a knee missing in most of those frames put there in every
    one of them; as it is when no knee is to be placed (none missing there, or no thigh and
    shank seen to measure).

    A knee missing in most frames is read from its hinge alone: its few seen frames disagree
    with the hinge by the pose model's own bias, a few degrees to tens, and the angles stepped
    between the two (a leg raised sideways, its lower knee missing for 1.4 s of every 2 s: 0
    repetitions of 2). A knee seen in most frames (at least :data:`MIN_VALID_SHARE`) is read
    where seen and placed where not, without the allowance for the legs' jitter below (a
    recording's knee missing through one exercise only: placed there; left out, the
    exercise's knee and hip angles were gone, a jog counted 1 of 7).

    The thigh and the shank are as long as the clip's median over both legs (a body is as long
    on the left as on the right); the knee lies at those lengths from the hip and the ankle
    (their distance fixes the knee's bend, by the law of cosines) and ahead of the line from
    hip to ankle, towards the chest's forward direction (a knee bends only backwards, the
    shank folding behind the thigh). The knee's and the hip's angles are then read as where
    the knee is seen, and take part in comparing the sides: the line from hip to ankle
    (:data:`LIMB_LINES`) stood in for the hip's angle alone, and hardly turns when the thigh
    rises and the shank hangs under it (knee raises and jogging steps were missed with a
    knee missing).

    A knee the camera does not see (:func:`_unseen`: its confidence below
    :data:`SEEN_CONFIDENCE`) is placed too, though the pose model wrote a guess for it (its
    angles are not read from the guess; before, it was neither read nor placed, and the leg
    read along its line). Only legs seen whole measure the thigh and the shank.

    Near a straight leg the bend hangs on a few centimetres of the hip-ankle distance (2 cm
    short of 0.74 m is 27 degrees), and a pose model's legs change length from frame to frame
    by as much: the distance is taken as longer by twice the standard deviation (robust,
    from the median absolute deviation) of the seen legs' length, so that what their own
    jitter makes a straight leg fall short by reads straight (a side plank's straight leg,
    its knee missing, counted two bends; motion capture's legs keep their length, and their
    knees are placed as before). Only for a knee missing in most frames: the seen frames of
    one seen in most were read with the jitter as it is, and the placed ones stepped away
    from them."""
    p = canonical.positions
    legs = [[_LEG["left"][i], _LEG["right"][i]] for i in range(3)]
    hip, knee, ankle = (p[:, joints] for joints in legs)
    seen = np.isfinite(p[:, sum(legs, [])]).all(axis=2)
    if canonical.confidence is not None:
        seen &= canonical.confidence[:, sum(legs, [])] >= SEEN_CONFIDENCE
    seen_hip, seen_knee, seen_ankle = seen[:, :2], seen[:, 2:4], seen[:, 4:]
    ends = np.isfinite(hip - ankle).all(axis=2)
    mostly_unseen = seen_knee.sum(axis=0) < MIN_VALID_SHARE * ends.sum(axis=0)
    place = ends & (~seen_knee | mostly_unseen)
    whole = seen_hip & seen_knee & seen_ankle
    thigh, shank = (
        np.linalg.norm(knee - hip, axis=2)[whole],
        np.linalg.norm(ankle - knee, axis=2)[whole],
    )
    if not place.any() or not whole.any():
        return canonical
    length = thigh + shank
    slack = 2.0 * MAD_TO_SD * float(np.median(np.abs(length - np.median(length))))
    thigh_m, shank_m = float(np.median(thigh)), float(np.median(shank))
    reach = np.minimum(
        np.linalg.norm(ankle - hip, axis=2, keepdims=True) + slack * mostly_unseen[None, :, None],
        thigh_m + shank_m,
    )
    along = unit(ankle - hip)
    forward = body_frame(p).forward[:, None, :]
    ahead = unit(forward - np.sum(forward * along, axis=2, keepdims=True) * along)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.clip((thigh_m**2 + reach**2 - shank_m**2) / (2 * thigh_m * reach), -1.0, 1.0)
    placed = hip + thigh_m * (cos * along + np.sqrt(1.0 - cos**2) * ahead)
    positions = p.copy()
    confidence = None if canonical.confidence is None else canonical.confidence.copy()
    for side, (h, k, a) in enumerate(_LEG.values()):
        at = place[:, side]
        positions[at, k] = placed[at, side]
        if confidence is not None:
            confidence[at, k] = np.minimum(confidence[at, h], confidence[at, a])
    return dataclasses.replace(canonical, positions=positions, confidence=confidence)


def _from_down(p: np.ndarray, root: str, end: str) -> np.ndarray:
    """``(frames,)`` the angle of the limb from ``root`` to ``end`` from straight down (the
    world's vertical), radians, of positions ``p`` ``(frames, 33, 3)``."""
    limb = p[:, JOINT_INDEX[end]] - p[:, JOINT_INDEX[root]]
    return angle_between(limb, np.broadcast_to(-WORLD_UP, limb.shape))


def _idle_lines(finite: np.ndarray, fps: float) -> list[int]:
    """The columns of :data:`COUNTED_ANGLES` of the :data:`STAND_INS` that take no part,
    from where each angle was computed, ``finite`` ``(frames, len(COUNTED_ANGLES))``: a stand-in
    takes part where its angle does not and the stand-in does (:func:`_kept`)."""
    kept = _kept(_followed(finite, fps).sum(axis=0), int(finite.any(axis=1).sum()))
    index = {n: i for i, n in enumerate(COUNTED_ANGLES)}
    used = {n for n, angle in STAND_INS.items() if kept[index[n]] and not kept[index[angle]]}
    return [index[n] for n in STAND_INS if n not in used]


def _swing(frm: np.ndarray, to: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``v`` turned by the shortest rotation taking unit ``frm`` to unit ``to`` (Rodrigues
    with axis ``frm x to``; all ``(frames, 3)``); NaN near the singular ``to = -frm``."""
    c = np.einsum("ij,ij->i", frm, to)[:, None]
    w = np.cross(frm, to)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = v * c + np.cross(w, v) + w * np.einsum("ij,ij->i", w, v)[:, None] / (1.0 + c)
    with np.errstate(invalid="ignore"):
        far = ~(c[:, 0] >= -TWIST_SINGULAR_COS)
    out[far] = np.nan
    return np.asarray(out)


def upper_arm_turn(p: np.ndarray) -> np.ndarray:
    """The forearms' direction away from the body's midline in a frame attached to the upper
    arms, ``(frames, 2)`` (left, right) from canonical positions ``(frames, 33, 3)``.

    The upper arm's frame is the trunk's (forward; down along the trunk) swung by the
    shortest rotation that takes "down along the trunk" to the upper arm; the forearm's unit
    direction along that frame's outward axis is the sine of the elbow bend times the sine
    of the upper arm's turn about its own axis (0 with the forearm ahead; mirror twins agree).
    An upper arm turning in and out with the elbow bent (shoulder internal and external
    rotation) moves it as far as the forearm swings, in radians for small turns; with the
    elbow straight it stays near 0. NaN where a joint is missing or the upper arm points up
    along the trunk (:data:`TWIST_SINGULAR_COS`)."""
    bf = body_frame(p)
    cols = []
    for side, outward in (("left", -1.0), ("right", 1.0)):
        shoulder, elbow, wrist = (p[:, JOINT_INDEX[f"{side}_{j}"]] for j in _ARM)
        axis = unit(elbow - shoulder)
        ahead = _swing(-bf.up, axis, bf.forward)
        # axis x ahead points to the person's right: away from the midline for the right arm
        out = outward * np.cross(axis, ahead)
        cols.append(np.einsum("ij,ij->i", unit(wrist - elbow), out))
    return np.stack(cols, axis=1)


def pelvis_height(p: np.ndarray) -> np.ndarray:
    """The hip centre's height above the floor, ``(frames,)``, in the clip's median trunk
    length (mid-hip to mid-shoulder; scale-free), from canonical positions ``(frames, 33, 3)``.
    The floor is where the lower ankle is in the clip's lowest 5 % (one number per clip: a
    hop lifts both feet, and a per-frame floor under the lower foot would rise with them).
    The whole body going up and down (a hop, a squat, sitting down), which no joint angle
    sees when the legs stay straight. Poses from video are measured from the hip centre,
    where this is constant and takes no part. NaN where a joint is missing."""
    mid_hip = 0.5 * (p[:, JOINT_INDEX["left_hip"]] + p[:, JOINT_INDEX["right_hip"]])
    neck = 0.5 * (p[:, JOINT_INDEX["left_shoulder"]] + p[:, JOINT_INDEX["right_shoulder"]])
    ankles = p[:, [JOINT_INDEX["left_ankle"], JOINT_INDEX["right_ankle"]]] @ WORLD_UP
    # all-NaN: no person, NaN out
    lower = over_seen(np.nanmin, ankles, 1)
    floor = over_seen(lambda v, axis: np.nanpercentile(v, 5, axis=axis), lower)
    trunk = over_seen(np.nanmedian, np.linalg.norm(neck - mid_hip, axis=1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray((mid_hip @ WORLD_UP - floor) / trunk)


def movement_signals(seq: PoseSequence) -> MovementSignals:
    """The counted angles of ``seq`` (positions ``(frames, joints, 3)``) ready for counting.

    Raises DataError when no angle is available in enough frames (no person in view)."""
    # SciPy in the functions that use it: importing this module (as cbr.problem does, for
    # every command that reads a case base) loads none
    from scipy.ndimage import gaussian_filter1d

    raw = counted_angles(seq)
    finite = np.isfinite(raw)
    followed = _followed(finite, seq.fps)
    shown = finite.any(axis=1)
    keep = _kept(followed.sum(axis=0), int(shown.sum()))
    if not keep.any():
        raise DataError(
            "no person in view in enough frames to follow a movement (joint angles missing)",
            seq.source or None,
        )
    names = tuple(n for n, k in zip(COUNTED_ANGLES, keep, strict=True) if k)
    step = max(1, int(round(seq.fps / ANALYSIS_FPS)))
    first = _first_step(seq.fps, step)  # frames apart the filters read (1 up to 240 fps)
    rate = seq.fps / first
    x = _interpolate(raw[:, keep])[::first]
    width = median_width(rate, seq.confidence is not None)
    x = _running_median(_drop_glitches(x, rate, width // 2 + 1), width)
    x = gaussian_filter1d(x, SMOOTHING_S * rate, axis=0, mode="nearest")[:: step // first]
    unseen = ~np.isfinite(raw[:, keep]).any(axis=1)
    blind = long_runs(unseen, MIN_PERIOD_S * seq.fps)[::step]
    samples = np.arange(0, seq.n_frames, step)  # sample i: frames [i step, (i + 1) step)
    return MovementSignals(
        x,
        names,
        seq.fps / step,
        step,
        blind if blind.any() else None,
        np.add.reduceat(followed[:, keep], samples, axis=0, dtype=np.int32),
        np.add.reduceat(shown, samples, dtype=np.int32),
    )


def glitch_free_fps() -> float:
    """The lowest frame rate at which the running median (:data:`MEDIAN_S`, 0.2 s) takes the
    three frames that drop a one-frame glitch of a pose model while the far half of the
    shortest repetition (:data:`MIN_PERIOD_S` / 2, 0.2 s) holds the two frames a median of
    three keeps: 10 fps."""
    return max(2.0 / MEDIAN_S, 4.0 / MIN_PERIOD_S)


def median_width(rate: float, estimated: bool) -> int:
    """How many samples (odd) the running median reads at ``rate``: :data:`MEDIAN_S`'s worth,
    and for poses a pose model ``estimated`` frame by frame (they carry its confidences)
    at least three below :func:`glitch_free_fps`, the fewest that drop a glitch of one frame
    (rounded, 0.2 s was one sample below 7.5 fps: no median, the glitches left in). Below
    10 fps three samples also drop the far point of the quickest repetitions, held for less
    than two (``reps``, ``segment`` and ``watch`` say so). Every k-th frame of videos of
    known count kept, more copies at 5-6 fps were counted exactly with three than with the
    rounded width. Recordings without confidences (motion capture) keep the rounded width:
    with none at 7.5-10 fps, mocap clips were counted better at 8 fps but a depth camera's
    recordings, whose pose model glitches though their files carry no confidences, worse
    (docs/measurements.md, "Figures behind the code's rules: Repetitions counted below 10
    fps")."""
    if estimated and rate < glitch_free_fps() - 1e-9:
        return 3
    return max(1, int(round(MEDIAN_S * rate)) | 1)


def _running_median(x: np.ndarray, width: int) -> np.ndarray:
    """The running median of ``x`` ``(n, C)`` over ``width`` samples (odd), each sample's window
    cut to the samples the clip has: near its start and end the median reads fewer samples,
    none made up. Padded with the edge sample (scipy's ``nearest``), the last sample's window
    held more copies of it than of anything else, so a pose model's glitch in the clip's last
    frame or two stood as a posture (a far point cut off by the end, counted, and gone a frame
    later when the median read past it; a knee the pose model bent for three frames made a
    count go up and back down as the clip grew); mirrored, a glitch just before the end is
    read twice. At
    30 fps (width 7) a glitch in the last frame is now gone and one in the last two halved.

    Column by column: SciPy's one-dimensional running median keeps its window sorted from
    sample to sample, where a ``(width, 1)`` filter over the whole array selects each median
    anew (the same medians, 6-12x the time: 3 s of a 10-minute recording at 120 fps)."""
    from scipy.ndimage import median_filter

    if np.isfinite(x).all():  # NaN sorts differently in the two (the callers give none)
        out = np.empty_like(x)
        for j in range(x.shape[1]):
            out[:, j] = median_filter(x[:, j], size=width, mode="nearest")
    else:
        out = median_filter(x, size=(width, 1), mode="nearest")
    half, n = width // 2, len(x)
    for i in range(min(half, n)):
        out[i] = np.median(x[: i + half + 1], axis=0)
        out[n - 1 - i] = np.median(x[max(0, n - 1 - i - half) :], axis=0)
    return np.asarray(out)


def _drop_glitches(x: np.ndarray, rate: float, shortest: int) -> np.ndarray:
    """``x`` ``(n, C)`` sampled at ``rate`` with a pose model's glitches put back that the
    running median (:data:`MEDIAN_S`) leaves: a run of at least ``shortest`` samples but
    shorter than half the shortest repetition (:data:`MIN_PERIOD_S`) in which an angle jumps
    away from the posture around it and back, each jump a sample apart (a lunge's legs
    swapped by the pose model for a few frames while she holds it still). Flagged where the
    angle lies away from its running median over twice that length by
    :data:`MIN_EXCURSION_RAD` and by more than 3 robust deviations of the window (Hampel's
    filter: a movement, whose samples spread over the window, is not), the run's first and
    last sample each at least :data:`JUMP_SHARE` of its farthest from the sample beside it (a
    kick's knee straightens and bends again as quickly, over several samples); such a run
    takes the median's values. Shorter runs are left to the running median, as before. Only
    the angles that jump that far somewhere are filtered (none, mostly: the medians cost
    their width at every sample)."""
    longest = int(np.ceil(0.5 * MIN_PERIOD_S * rate)) - 1
    width = 2 * longest + 1
    if longest < max(1, shortest) or len(x) < width:
        return x
    cols = np.flatnonzero((np.abs(np.diff(x, axis=0)) > JUMP_SHARE * MIN_EXCURSION_RAD).any(axis=0))
    if not len(cols):
        return x
    part = x[:, cols]
    centre = _running_median(part, width)
    dev = part - centre
    spread = MAD_TO_SD * _running_median(np.abs(dev), width)
    flagged = np.abs(dev) > np.maximum(3.0 * spread, MIN_EXCURSION_RAD)
    out = x.copy()
    for k, j in enumerate(cols):
        edges = np.flatnonzero(np.diff(np.concatenate([[0], flagged[:, k].astype(np.int8), [0]])))
        for a, b in zip(edges[::2], edges[1::2], strict=True):
            if not shortest <= b - a <= longest or a == 0 or b == len(x):
                continue
            far = float(np.abs(dev[a:b, k]).max())
            jumps = abs(x[a, j] - x[a - 1, j]), abs(x[b, j] - x[b - 1, j])
            if min(jumps) >= JUMP_SHARE * far:
                out[a:b, j] = centre[a:b, k]
    return out


def _first_step(fps: float, step: int) -> int:
    """Every how many frames the running median and the smoothing read a clip at ``fps``
    analysed every ``step`` frames: 1 up to :data:`MAX_FILTER_FPS`, above it the largest
    divisor of ``step`` that leaves at least that rate (the analysed samples stay every
    ``step``-th frame)."""
    fits = [d for d in range(1, step + 1) if step % d == 0 and fps / d >= MAX_FILTER_FPS]
    return max(fits, default=1)


def _in_view(far: np.ndarray, blind: np.ndarray | None) -> np.ndarray:
    """Where the far points ``far`` (samples, ascending) were seen: one in a ``blind``
    stretch moved to the nearest sample seen (the values there are the last or next posture
    seen, held, a plateau whose middle the peak finder names, or interpolated). Ascending,
    as long as ``far`` (two may land on one sample); empty when no sample is seen."""
    if blind is None or not len(far) or not blind[far].any():
        return far
    seen = np.flatnonzero(~blind)
    if not len(seen):
        return far[:0]
    at = np.clip(np.searchsorted(seen, far), 1, len(seen) - 1)
    before, after = seen[at - 1], seen[at]
    nearest = np.where(far - before <= after - far, before, after)
    return np.where(blind[far], nearest, far)


def _seen_spans(
    spans: list[tuple[int, int]], far: np.ndarray, blind: np.ndarray | None
) -> list[tuple[int, int]]:
    """Each repetition's span ``[a, b)`` cut to the stretch seen around its far point (the
    far points are seen, :func:`_in_view`): a repetition next to a stretch with nobody seen
    starts where the person is first seen, not where the held posture began (with a
    recording's first seconds blank, its first repetition started seconds into the blank)."""
    if blind is None:
        return spans
    out = []
    for (a, b), p in zip(spans, far, strict=True):
        before = np.flatnonzero(blind[a:p])
        after = np.flatnonzero(blind[p:b])
        out.append((a + int(before[-1]) + 1 if len(before) else a,
                    p + int(after[0]) if len(after) else b))  # fmt: skip
    return out


_TRUNK = ("left_shoulder", "right_shoulder", "left_hip", "right_hip")
_ARM = ("shoulder", "elbow", "wrist")
_ANGLE_JOINTS: dict[str, tuple[str, ...]] = {
    **{f"{s}_elbow": (f"{s}_shoulder", f"{s}_elbow", f"{s}_wrist") for s in ("left", "right")},
    **{f"{s}_knee": (f"{s}_hip", f"{s}_knee", f"{s}_ankle") for s in ("left", "right")},
    **{f"{s}_armpit": (f"{s}_elbow", f"{s}_shoulder", f"{s}_hip") for s in ("left", "right")},
    **{f"{s}_hip": (f"{s}_knee", f"{s}_hip", f"{s}_shoulder") for s in ("left", "right")},
    **{n: _TRUNK for n in COUNTED_ANGLES if n.startswith(("trunk_", "torso_"))},
    **{f"{s}_upper_arm_turn": (*(f"{s}_{j}" for j in _ARM), *_TRUNK) for s in ("left", "right")},
    PELVIS_HEIGHT: (*_TRUNK, "left_ankle", "right_ankle"),
    **{n: js for n, (_, js) in LIMB_LINES.items()},
    **{n: js for n, (_, js) in ARM_RAISES.items()},
}


_ON_LEGS = np.array([bool(SWAP_JOINTS.intersection(_ANGLE_JOINTS[n])) for n in COUNTED_ANGLES])
"""Which of :data:`COUNTED_ANGLES` rest on a joint a swap of the legs moves
(:data:`features.leg_swaps.SWAP_JOINTS`): missing where the pose model swapped the legs."""


SEEN_CONFIDENCE = 0.5
"""A joint whose confidence (the pose model's visibility) is below this is not seen
(:func:`_unseen`)."""


def _unseen(confidence: np.ndarray | None) -> np.ndarray:
    """``(frames, len(COUNTED_ANGLES))`` True where an angle rests on a joint the camera does
    not see (visibility below :data:`SEEN_CONFIDENCE`): the pose model guesses such joints,
    it does not measure them. ``confidence``: ``(frames, 33)`` on the canonical skeleton."""
    assert confidence is not None
    seen = confidence >= SEEN_CONFIDENCE
    cols = [
        np.all(seen[:, [JOINT_INDEX[j] for j in _ANGLE_JOINTS[n]]], axis=1) for n in COUNTED_ANGLES
    ]
    return np.asarray(~np.stack(cols, axis=1))


def _followed(finite: np.ndarray, fps: float) -> np.ndarray:
    """``(frames, n)``: where each angle (``finite``: where it was computed) is seen or lies
    in a gap of at most :data:`MAX_FILLED_GAP_S` (at least one frame). An angle seen in no
    frame is followed in none: a clip shorter than that gap is not one gap to fill, there
    being no value to fill it from."""
    longest = max(1, int(round(MAX_FILLED_GAP_S * fps)))
    out = finite.copy()
    for j in np.flatnonzero(~finite.all(axis=0) & finite.any(axis=0)):
        out[:, j] |= ~long_runs(~finite[:, j], longest + 1)
    return out


def _interpolate(x: np.ndarray) -> np.ndarray:
    """NaN along time filled linearly (edges hold the nearest value); ``(frames, n)``."""
    nan = np.isnan(x)
    if not nan.any():
        return x
    out = x.copy()
    t = np.arange(len(x))
    for j in np.flatnonzero(nan.any(axis=0)):  # over the few gappy channels only
        ok = ~nan[:, j]
        out[:, j] = np.interp(t, t[ok], x[ok, j])
    return out


def _lagged_products(x: np.ndarray) -> np.ndarray:
    """Per channel, the products of the centred ``x`` ``(n, channels)`` with itself at every
    lag, averaged over the frames each lag overlaps: ``(n, channels)``."""
    from scipy.fft import next_fast_len

    n = len(x)
    xc = x - x.mean(axis=0)
    size = next_fast_len(2 * n)
    spec = np.fft.rfft(xc, size, axis=0)
    acov = np.fft.irfft((spec * spec.conj()).real, size, axis=0)[:n]
    return np.asarray(acov / (n - np.arange(n))[:, None])


def autocorrelation(x: np.ndarray) -> np.ndarray:
    """Summed autocorrelation of the centred channels of ``x`` ``(n, channels)``, each lag
    averaged over the frames it overlaps and divided by lag 0: ``(n,)``."""
    acf = _lagged_products(x).sum(axis=1)
    return acf / acf[0] if acf[0] > 0 else np.zeros(len(x))


def periodic_share(x: np.ndarray, period: float | None, fps: float) -> np.ndarray:
    """Per channel of ``x`` ``(n, channels)``, the share of its variance that recurs one
    ``period`` later: its autocorrelation at that lag over lag 0, weighted by the lag's
    overlap as :func:`find_period` weighs it, clipped to [0, 1] (1 = exact repetition, 0 =
    noise or a one-off change) ``(channels,)``; all 1 without a period."""
    if period is None:
        return np.ones(x.shape[1])
    n = len(x)
    lag = min(n - 1, int(round(period * fps)))
    acov = _lagged_products(x)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = acov[lag] / acov[0] * (1.0 - lag / n)
    return np.asarray(np.clip(np.nan_to_num(share), 0.0, 1.0))


def find_period(x: np.ndarray, fps: float) -> tuple[float | None, float]:
    """The period (seconds) of ``x`` ``(n, channels)`` and its autocorrelation there.

    Lags from :data:`MIN_PERIOD_S` to 60 % of the clip (a lag needs a good share of the clip
    to overlap), each weighted by its overlap (1 - lag / n: the biased estimator, whose
    variance at long lags stays small); the shortest local maximum within 85 % of the highest
    one, so that a multiple of the period does not win by noise. (None, 0.0) when nothing
    repeats."""
    n = len(x)
    lo, hi = int(np.ceil(MIN_PERIOD_S * fps)), int(0.6 * n)
    if hi <= lo + 2:
        return None, 0.0
    acf = autocorrelation(x) * (1.0 - np.arange(n) / n)
    from scipy.signal import find_peaks  # here: scipy.signal costs 0.6 s to import

    peaks, _ = find_peaks(acf[: hi + 1])
    peaks = peaks[(peaks >= lo) & (acf[peaks] > 0)]
    if not len(peaks):
        return None, 0.0
    best = peaks[acf[peaks] >= 0.85 * acf[peaks].max()][0]
    return float(best / fps), float(acf[best])


def mirror_matrix(names: tuple[str, ...]) -> np.ndarray:
    """``(C, C)`` linear map of angle deviations to those of the left-right mirror image:
    left and right twins swap, sideways tilts and turns of the trunk change sign."""
    index = {n: i for i, n in enumerate(names)}
    m = np.zeros((len(names), len(names)))
    for i, n in enumerate(names):
        m[index.get(_swap(n), i), i] = -1.0 if n in _LATERAL else 1.0
    return m


def movement_direction(x: np.ndarray) -> np.ndarray:
    """The unit direction ``(C,)`` in joint-angle space along which ``x`` ``(n, C)`` moves back
    and forth most: the first principal direction of its velocities (a one-off change of
    posture, such as stepping into the exercise, moves once; repetitions move many times)."""
    v = np.diff(x, axis=0)
    if not len(v) or not np.any(v):
        return np.asarray(np.eye(x.shape[1])[0])
    with one_blas_thread():  # samples by a few angles: BLAS's threads only wait for each other
        _, _, vt = np.linalg.svd(v - v.mean(axis=0), full_matrices=False)
    return np.asarray(vt[0])


def side_parts(x: np.ndarray, names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The deviations of ``x`` ``(n, C)`` from the left-right symmetric mean posture, split
    into what both sides do alike (``sym``) and what one side does against the other
    (``anti``; 0 = a symmetric posture): two ``(n, C)`` arrays summing to the deviations."""
    m = mirror_matrix(names)
    mean = x.mean(axis=0)
    centre = 0.5 * (mean + mirror_angles(mean[None], names)[0])
    d = x - centre
    md = d @ m.T
    return 0.5 * (d + md), 0.5 * (d - md)


def _movement_line(
    x: np.ndarray, names: tuple[str, ...], direction: np.ndarray, fps: float
) -> np.ndarray:
    """The movement as one number per sample: the posture ``x`` ``(n, C)`` at ``fps``
    projected on the movement ``direction`` ``(C,)``, signed so that it rises away from rest
    (:func:`_rest_is_high`)."""
    line = (x - x.mean(axis=0)) @ direction
    if _rest_is_high(x, names, direction, line, fps):
        line = -line
    return np.asarray(line)


def _rest_is_high(
    x: np.ndarray, names: tuple[str, ...], direction: np.ndarray, line: np.ndarray, fps: float
) -> bool:
    """Whether the rest end of the movement is the high end of ``line`` ``(n,)``: the end
    whose trunk tilts less far head-down past the horizontal, when the two ends differ in it
    by :data:`MIN_EXCURSION_RAD` (hips held up above the shoulders, a bridge lying on the
    back, are no rest; standing at ease would name the bridge, whose hips straighten); else
    the end nearer :data:`AT_EASE`, when the angles that have an at-ease value carry at least
    :data:`EASE_SHARE` of the movement (the upper arm's turn has no side nearer ease, the hips'
    height no value at ease common to all bodies, a limb's line, :data:`LIMB_LINES`, folds
    the limb's turn in: a movement mostly along them, a shoulder turning in and out, is not told
    by the elbow's small part in it) and one end lies nearer
    it by :data:`MIN_EXCURSION_RAD`, summed angle by angle (an angle as far from ease at both
    ends adds nothing); otherwise the end
    the clip's first and last :data:`ENDS_S` seconds lie nearer (an exercise starts and ends
    at rest)."""
    ease = np.array([AT_EASE.get(n, np.pi / 2) for n in names])
    lo, hi = _end_levels(line)
    low_posture = x[line <= lo].mean(axis=0)
    high_posture = x[line >= hi].mean(axis=0)
    free = np.array([n in TWIST_NAMES or n == PELVIS_HEIGHT or n in LIMB_LINES for n in names])
    high_posture[free] = low_posture[free] = ease[free]
    # how much nearer ease one end lies than the other, angle by angle (radians summed): an
    # angle that stays far from ease at both ends (lying on the side, the lower arm bent under
    # the head) adds nothing, where in the distances' difference it swamped the angles that
    # move and left the ends undecided
    # (> 0: the low end nearer ease)
    nearer_low = float(np.sum(np.abs(high_posture - ease) - np.abs(low_posture - ease)))
    if "trunk_inclination" in names:
        # the hips held up above the shoulders (a bridge) are no rest: the end whose trunk
        # tilts less far head-down past the horizontal is, whatever standing at ease says
        i = names.index("trunk_inclination")
        high_past, low_past = (
            max(0.0, float(p[i]) - np.pi / 2) for p in (high_posture, low_posture)
        )
        if abs(high_past - low_past) >= MIN_EXCURSION_RAD:
            return high_past < low_past
    eased = float(np.sum(direction[~free] ** 2) / max(float(np.sum(direction**2)), 1e-12))
    if eased >= EASE_SHARE and abs(nearer_low) >= MIN_EXCURSION_RAD:
        return nearer_low < 0
    k = _ends_samples(len(line), fps)
    ends = float(np.concatenate([line[:k], line[-k:]]).mean())
    return bool(abs(ends - hi) < abs(ends - lo))


def _end_levels(line: np.ndarray) -> tuple[float, float]:
    """The levels below and above which ``line`` ``(n,)`` lies at its two ends: its outer
    tenth of the frames, or of its range when fewer frames reach that far (a clip mostly at
    rest: its tenths by frames both lie in the rest)."""
    lo, hi = np.percentile(line, [10, 90])
    low_end, high_end = float(line.min()), float(line.max())
    lo = min(float(lo), low_end + 0.1 * (high_end - low_end))
    hi = max(float(hi), high_end - 0.1 * (high_end - low_end))
    return lo, hi


def _ends_samples(n: int, fps: float) -> int:
    """How many samples the clip's first and last :data:`ENDS_S` seconds hold (of ``n``)."""
    return min(n // 2, max(1, int(round(ENDS_S * fps))))


def _held_change(
    x: np.ndarray, line: np.ndarray, fps: float, peak: int, ends: tuple[bool, bool] = (True, True)
) -> bool:
    """Whether the clip ``x`` ``(n, C)`` goes from one end of its movement ``line`` ``(n,)``
    to the other and holds still there: its first :data:`ENDS_S` seconds' posture lies nearer
    one end's posture (the mean posture where the line lies at that end, :func:`_end_levels`)
    and its last nearer the other's, each by :data:`MIN_EXCURSION_RAD` (distances over all
    the counted angles, which the line is read from), and the line moves less than
    :data:`MIN_EXCURSION_RAD` in all over the clip's last :data:`MIN_PERIOD_S` (over its
    first, for a clip that starts at the far end and ends at rest): no repetition is under
    way there, none being smaller or quicker. A clip with one far point that does so went
    out once and stayed (getting into a side plank and holding it), or left a posture held
    from its start: a change of posture, not a repetition cut off by the clip's end or start
    (which is still under way there). Unless the line had come back from the far point
    ``peak`` by :data:`MIN_EXCURSION_RAD` before it stopped (:func:`_returned_before_hold`):
    that is a repetition paused on its way back (sitting a moment after sitting down), no
    posture held; a side plank's sag comes during the hold.

    ``ends``: whether the clip's start, and its end, may be read as a posture's (the
    recording's, or a cut beyond which nothing turns): a posture got into and held needs
    its end, one held from the start and left needs its start. The other end may be a cut
    into the recording (a segment): the posture at a cut is judged by where it lies, as at
    the recording's start (a side plank got into after the exercise before it and held to
    the recording's end; before, its segment counted 1 while ``reps`` on the plank alone
    counted 0)."""
    lo, hi = _end_levels(line)
    low, high = x[line <= lo].mean(axis=0), x[line >= hi].mean(axis=0)
    k = _ends_samples(len(line), fps)
    sides = []
    for posture in (x[:k].mean(axis=0), x[-k:].mean(axis=0)):
        nearer_high = float(np.linalg.norm(posture - low) - np.linalg.norm(posture - high))
        sides.append(0.0 if abs(nearer_high) < MIN_EXCURSION_RAD else float(np.sign(nearer_high)))
    m = min(len(line) - 1, max(1, int(round(MIN_PERIOD_S * fps))))
    still_start = float(np.abs(np.diff(line[: m + 1])).sum()) < MIN_EXCURSION_RAD
    still_end = float(np.abs(np.diff(line[-m - 1 :])).sum()) < MIN_EXCURSION_RAD
    held_end = still_end and not _returned_before_hold(line, peak, m)
    held_start = still_start and not _returned_before_hold(line[::-1], len(line) - 1 - peak, m)
    into = ends[1] and sides[0] < 0 < sides[1] and held_end
    left = ends[0] and sides[0] > 0 > sides[1] and held_start
    return into or left


def _returned_before_hold(line: np.ndarray, peak: int, m: int) -> bool:
    """Whether ``line`` ``(n,)`` falls back from its far point ``peak`` by
    :data:`MIN_EXCURSION_RAD` before the still stretch it ends in begins: after the last
    ``m`` samples (:data:`MIN_PERIOD_S`) over which it spans that far (its highest less its
    lowest). A far point within the still stretch (reached while holding, or as the line
    stopped) has not. Spans, not movement in all: a wobble out and back within the hold
    moves twice its size (a side plank's, re-encoded in a joined video: 11 degrees down and
    up again in 0.4 s, 17 in all, read as the hold's start 0.4 s before the end, and the
    sag before it as a return: 1 repetition, the clip alone 0)."""
    from numpy.lib.stride_tricks import sliding_window_view

    windows = sliding_window_view(line, min(len(line), m + 1))
    moved = windows.max(axis=1) - windows.min(axis=1) >= MIN_EXCURSION_RAD
    hold = int(np.flatnonzero(moved)[-1]) + m if moved.any() else 0
    if peak >= hold:
        return False
    return bool(line[peak] - line[peak : hold + 1].min() >= MIN_EXCURSION_RAD)


def _far_points(
    line: np.ndarray, rest: float, distance: int, reach: int | None = None, still: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    """Samples where ``line`` reaches a far point: peaks that stand out by at least
    :data:`SUBSTANTIAL` of the typical repetition (the median prominence of the candidates) and by
    :data:`MIN_EXCURSION_RAD`, from which the line falls back on both sides by at least
    :data:`RETURN_SHARE` of their height above ``rest`` (a peak after a shallow dip belongs to
    the repetition before it), at least ``distance`` samples apart. The clip is padded with
    the rest level, so a repetition cut off at either end (the line falls back from it by less
    than :data:`MIN_EXCURSION_RAD` before the clip's start or after its end, a tail that only
    levels off) counts when it got (nearly) as far as the others (:func:`_reached`). Returns
    the far points and how far the line rises to each and falls back from it within the clip
    (``(k, 2)``, :func:`_candidates`). ``reach``: a far point's height is taken above the
    lowest of the line around it (:func:`_floors`, within ``reach`` samples), or above
    ``rest`` when that is higher or ``reach`` is None; ``still``: samples of
    :data:`MIN_PERIOD_S`."""
    cand, back = _candidates(line, rest, distance, reach, still)
    keep = _reached(line[cand] - rest, back)
    return np.asarray(cand[keep]), back[keep]


def _candidates(
    line: np.ndarray, rest: float, distance: int, reach: int | None = None, still: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_far_points` before the cut-off ones are judged: the samples, and how far the
    line rises to each from its lowest since the clip's start and falls back from it to its
    lowest until the clip's end, ``(k, 2)`` (below :data:`MIN_EXCURSION_RAD`: cut off there)."""
    padded = np.concatenate([[rest], line, [rest]])
    from scipy.signal import find_peaks

    cand, props = find_peaks(padded, prominence=MIN_EXCURSION_RAD, distance=max(1, distance))
    if not len(cand):
        return np.array([], dtype=np.int64), np.zeros((0, 2))
    prom = props["prominences"]
    height = padded[cand] - rest
    if reach is not None:
        height = padded[cand] - np.maximum(rest, _floors(line, cand - 1, reach, rest, still))
    keep = (prom >= SUBSTANTIAL * float(np.median(prom))) & (prom >= RETURN_SHARE * height)
    cand = cand[keep] - 1
    before = np.minimum.accumulate(line)[cand]
    after = np.minimum.accumulate(line[::-1])[::-1][cand]
    return np.asarray(cand), np.stack([line[cand] - before, line[cand] - after], axis=1)


def _floors(line: np.ndarray, peaks: np.ndarray, reach: int, rest: float, still: int) -> np.ndarray:
    """Per peak of ``line`` ``(n,)`` (samples ``peaks``, ascending), the lowest of the line
    from the peak before it to the peak after it and within ``reach`` samples of it: the low
    points of its own repetition. Before the first peak and after the last, ``rest`` unless
    the line is still at the clip's start (or end): moving less than
    :data:`MIN_EXCURSION_RAD` in all over its first (last) ``still`` samples. A clip cut
    while the line falls from its last far point does not show how far it falls (padded
    with the rest level, as :func:`_candidates` pads it): a sit-to-stand's second dip of
    the knees, on the way up, is no repetition of its own whatever the clip's end."""
    from scipy.ndimage import minimum_filter1d

    n = len(line)
    lowest = minimum_filter1d(line, size=2 * max(1, reach) + 1, mode="nearest")[peaks]
    bounds = np.concatenate([[0], peaks, [n - 1]])
    span = np.array([line[a : b + 1].min() for a, b in zip(bounds[:-2], bounds[2:], strict=True)])
    m = min(n - 1, max(1, still))
    if float(np.abs(np.diff(line[: m + 1])).sum()) >= MIN_EXCURSION_RAD:
        span[0] = min(float(span[0]), rest)
    if float(np.abs(np.diff(line[-m - 1 :])).sum()) >= MIN_EXCURSION_RAD:
        span[-1] = min(float(span[-1]), rest)
    return np.asarray(np.minimum(lowest, span))


def _reached(height: np.ndarray, back: np.ndarray) -> np.ndarray:
    """Which far points count, of heights ``height`` above rest, the line rising to them and
    falling back from them by ``back`` ``(k, 2)`` within the clip (:func:`_candidates`; cut
    off at the clip's start or end below :data:`MIN_EXCURSION_RAD`): every whole one, and one
    cut off when it got (nearly) as far as the whole ones: three quarters of their median
    height, or :data:`TURNED_SHARE` of it when the line has turned at it within the clip
    (all, when none is whole: :func:`_whole_only` judges those)."""
    cut = back < MIN_EXCURSION_RAD
    whole = ~cut.any(axis=1)
    if not whole.any():
        return np.ones(len(height), dtype=bool)
    turned = ~(cut & (back <= 0.0)).any(axis=1)
    share = np.where(turned, TURNED_SHARE, 0.75)
    return np.asarray(whole | (height >= share * float(np.median(height[whole]))))


def _whole_only(back: np.ndarray, edges: tuple[bool, bool]) -> np.ndarray:
    """Which far points count, the line rising to them and falling back from them by
    ``back`` ``(k, 2)`` within the clip (:func:`_candidates`), when the clip's start and its
    end are the recording's as ``edges`` says: all when one of them is whole (rising and
    falling back by :data:`MIN_EXCURSION_RAD`: the movement turns there); otherwise none cut
    off at the recording's start or end. A clip without one whole repetition (only the way
    down of a squat, half an arm circle) has none: before, its far point, cut off with
    nothing whole to be measured against, counted as a repetition. A far point cut off where
    a longer recording was cut into pieces stays: :func:`cbr.segmentation.keep_whole` gives
    it to one piece."""
    short = back < MIN_EXCURSION_RAD
    if not len(back) or (~short.any(axis=1)).any():
        return np.ones(len(back), dtype=bool)
    return np.asarray(~(short & np.array(edges)).any(axis=1))


def _beyond(height: np.ndarray, far: np.ndarray) -> np.ndarray:
    """Which of the candidate far points ``far`` of one side of an alternating movement go
    out beyond the symmetric posture (``height`` > 0) by at least :data:`SUBSTANTIAL` of
    their median: a peak's prominence is measured down to the other side's far points around
    it, so a wobble just past the symmetric posture between two of those stands out as much
    as a repetition (a street's walkers, 0.5-5 degrees, among steps of 15-35)."""
    out = height[far] > 0
    if out.any():
        out &= height[far] >= SUBSTANTIAL * float(np.median(height[far][out]))
    return np.asarray(out)


def _span(line: np.ndarray) -> float:
    """The robust range of a line: 5th to 95th percentile."""
    lo, hi = np.percentile(line, [5, 95])
    return float(hi - lo)


def _bounds(
    line: np.ndarray, peaks: np.ndarray, reach: int, held: bool = True
) -> list[tuple[int, int]]:
    """Each peak's repetition as samples [start, end) of ``line`` ``(n,)``: from the lowest
    point since the previous peak to the lowest point before the next one, where the next
    repetition starts; the first from where the movement leaves rest before its peak, the last
    to where it returns to rest after its peak (:func:`_leaves_rest`, about the lowest point
    within ``reach`` samples). The spans follow one another without overlap and each holds its
    peak (``peaks`` ascending, distinct): the lowest point between two peaks is sought after
    the first, so a peak lower than all that follows it up to the next (the other side's
    barely past the symmetric posture) is a repetition of one sample, not of none. A first
    (last) peak held for ``reach`` samples or more before (after) it, with ``held``, has its
    low point sought within ``reach`` of where the hold begins (ends): the squat held 12 s
    runs from the way down to where the body is back up (:func:`_above_rest`)."""
    n = len(line)
    cuts = [
        int(a + 1 + np.argmin(line[a + 1 : b + 1]))
        for a, b in zip(peaks[:-1], peaks[1:], strict=True)
    ]
    first_peak, last_peak = int(peaks[0]), int(peaks[-1])
    # a far point held for longer than ``reach`` (a squat held 12 s at the bottom) is left
    # and come back to beyond its hold: sought within ``reach`` of the hold's ends
    held_from, held_to = _hold(line, first_peak)[0], _hold(line, last_peak)[1]
    if not held:
        held_from, held_to = first_peak, last_peak
    first_lo = max(0, first_peak - reach)
    if held_from <= first_peak - reach:
        first_lo = max(0, held_from - reach)
    low = first_lo + int(np.argmin(line[first_lo : first_peak + 1]))
    first = low + _leaves_rest(line[low : first_peak + 1])
    last_hi = min(n, last_peak + reach + 1)
    if held_to >= last_peak + reach:
        last_hi = min(n, held_to + reach + 1)
    low = last_peak + int(np.argmin(line[last_peak:last_hi]))
    last = low - _leaves_rest(line[last_peak : low + 1][::-1])  # read back from the low point
    return list(zip([first, *cuts], [*cuts, last + 1], strict=True))


def _leaves_rest(rise: np.ndarray) -> int:
    """The last sample of ``rise`` ``(k,)`` (a line from its low point, ``rise[0]``, to a
    peak, ``rise[-1]``) that lies within :data:`LEAVE_SHARE` of the peak's height above the
    low point: where the movement leaves rest (0 when it rises at once)."""
    level = rise[0] + LEAVE_SHARE * (rise[-1] - rise[0])
    return int(np.flatnonzero(rise <= level)[-1])


def _sides(
    x: np.ndarray,
    names: tuple[str, ...],
    one: np.ndarray,
    other: np.ndarray,
    direction: np.ndarray,
) -> str:
    """Which side the far points ``one`` (samples of ``x`` ``(n, C)`` on one side of the
    symmetric posture) go out to, the far points ``other`` going out to the other: "left"
    when the left limbs' angles lie farther from their mean posture, against the right
    limbs', at ``one``'s far points than at ``other``'s. When the trunk carries the movement
    ``direction`` ``(C,)`` (:data:`TRUNK_SIDE_SHARE`), "left" when the trunk is turned or
    leans farther to the left at ``one``'s far points than at ``other``'s (its sideways
    angles, each weighted by its share of the direction, lower: below 90 degrees is left).

    Compared between the two sides' far points, not within one: in a jog both legs and arms
    move at every step, and a person whose right arm swings wider makes every step look
    right-sided (a jog's steps were named right but one in five); what changes
    between a left step and a right one is which side leads."""
    trunk = np.array([n in _LATERAL for n in names])
    if float(direction[trunk] @ direction[trunk]) >= TRUNK_SIDE_SHARE:
        lean = x[:, trunk] @ np.abs(direction[trunk])
        return "left" if lean[one].mean() <= lean[other].mean() else "right"
    dev = np.abs(x - x.mean(axis=0))
    left = np.array([n.startswith("left_") for n in names])
    right = np.array([n.startswith("right_") for n in names])
    lead = dev[:, left].sum(axis=1) - dev[:, right].sum(axis=1)
    return "left" if lead[one].mean() >= lead[other].mean() else "right"


def count_repetitions(
    seq: PoseSequence, recording_edges: bool | tuple[bool, bool] = True
) -> RepetitionCount:
    """The repetitions in ``seq`` (positions ``(frames, joints, 3)``): see the module docstring.

    ``recording_edges``: the clip starts and ends where its recording does, so that a clip
    whose one far point the body went out to and held still until the end is a change of
    posture, no repetition (:func:`_held_change`); False for a piece cut out of a longer
    recording (a segment), whose far point at a cut is handed to the piece beyond it
    (:func:`cbr.segmentation.keep_whole`) and must stay; or a pair, for the clip's start and
    its end (:func:`count_in_signals`). A recording whose person is lost from view for good
    before its end, or first seen after its start, is counted on the frames that show the
    person (:func:`seen_frames`). Raises DataError when the clip is
    shorter than one repetition could be (:data:`MIN_PERIOD_S`) or shows no person, and
    InputError when ``seq`` is not a PoseSequence (an array: ``PoseSequence(xyz, names,
    fps)`` makes one)."""
    expect_sequence(seq)
    if seq.duration_s < MIN_PERIOD_S:
        raise DataError(
            f"the clip lasts {seq.duration_s:.2f} s, shorter than one repetition can be"
            f" ({MIN_PERIOD_S:g} s)",
            seq.source or None,
        )
    check_person(seq, "count", arms=True)
    sig = movement_signals(seq)
    a, b = seen_frames(seq, sig, recording_edges)
    if (a, b) != (0, seq.n_frames):
        return count_seen(seq, a, b, lambda piece: count_repetitions(piece, recording_edges))
    return count_in_signals(sig, seq.n_frames, seq.fps, recording_edges)


def seen_frames(
    seq: PoseSequence, sig: MovementSignals, recording_edges: bool | tuple[bool, bool] = True
) -> tuple[int, int]:
    """Frames [a, b) of recording ``seq`` whose movement signals are ``sig``, from the first
    that shows the person to the last: without the stretch of at least
    :data:`MIN_PERIOD_S` with nobody in view (:attr:`MovementSignals.blind`) that it starts
    with, or ends with, where that is the recording's start or end (``recording_edges``, as
    :func:`count_repetitions` takes it; at a cut into pieces, such a stretch is the
    segmentation's: :func:`cbr.segmentation.counted_segments`). The whole recording when
    neither, or when nobody is seen in it. Found on the samples of ``sig``, to the frame
    within the sample: the first (last) with a joint seen.

    The view of the movement ends where the person is lost for good, as it ends where the
    recording does: counted on the frames that show the person (:func:`count_seen`), a far
    point cut off there counts as one cut off by the recording's end (none without a whole
    repetition: the way down of a squat, the person then lost, is no repetition). Before,
    the posture last seen was held through the rest and smoothed into it, and such a far
    point counted: the way down of a squat after two squats, then nobody, counted 3 where
    the recording ending at the same frame counts 2."""
    edges = (
        (recording_edges, recording_edges)
        if isinstance(recording_edges, bool)
        else (bool(recording_edges[0]), bool(recording_edges[1]))
    )
    blind, step, n_frames = sig.blind, sig.step, seq.n_frames
    if blind is None or not (blind[0] and edges[0] or blind[-1] and edges[1]):
        return 0, n_frames
    seen = np.flatnonzero(~blind)
    if not len(seen):
        return 0, n_frames
    a, b = 0, n_frames
    if edges[0] and blind[0]:  # the frames of the sample before the first seen, and its own
        lo = max(0, (int(seen[0]) - 1) * step)
        shown = _any_joint(seq.positions[lo : (int(seen[0]) + 1) * step])
        a = lo + int(np.argmax(shown)) if shown.any() else int(seen[0]) * step
    if edges[1] and blind[-1]:  # the last seen sample's frames, and the next sample's
        lo = int(seen[-1]) * step
        shown = _any_joint(seq.positions[lo : min(n_frames, lo + 2 * step)])
        b = lo + int(np.flatnonzero(shown)[-1]) + 1 if shown.any() else lo + 1
    return a, b


def _any_joint(positions: np.ndarray) -> np.ndarray:
    """``(frames,)`` whether any joint of ``positions`` ``(frames, joints, 3)`` is seen."""
    return np.asarray(np.isfinite(positions).all(axis=2).any(axis=1))


def count_seen(
    seq: PoseSequence, a: int, b: int, count: Callable[[PoseSequence], RepetitionCount]
) -> RepetitionCount:
    """The repetitions of frames [a, b) of ``seq`` (:func:`seen_frames`), counted by
    ``count`` as a clip of their own, the frames numbered in ``seq``: none when they are
    shorter than one repetition could be (:data:`MIN_PERIOD_S`). The joint angles already
    computed for ``seq`` are shared (:func:`features.derived.stretch`)."""
    piece = stretch(seq, a, b)
    if piece.duration_s < MIN_PERIOD_S:
        return RepetitionCount((), seq.fps, seq.n_frames, None, 0.0, False, ())
    found = count(piece)
    reps = tuple(
        dataclasses.replace(
            r, start_frame=r.start_frame + a, end_frame=r.end_frame + a, peak_frame=r.peak_frame + a
        )
        for r in found.repetitions
    )
    return dataclasses.replace(found, repetitions=reps, n_frames=seq.n_frames)


def person_jumps(seq: PoseSequence) -> list[int]:
    """The frames at which ``seq``'s pose jumped to another person, as its pose file's
    metadata records them (``person_jumps``, :func:`features.pose_estimation.video.person_jumps`;
    inside the clip, ascending; none when it records none it can read)."""
    record = seq.metadata.get("person_jumps")
    frames = record.get("frames") if isinstance(record, dict) else None
    if not isinstance(frames, list):
        return []
    offset = seq.metadata.get("frame_offset", 0)
    offset = offset if isinstance(offset, int) else 0
    inside = {f - offset for f in frames if isinstance(f, int) and not isinstance(f, bool)}
    return sorted(f for f in inside if 0 < f < seq.n_frames)


def count_apart(
    seq: PoseSequence,
    cuts: Sequence[int],
    count: Callable[[PoseSequence], RepetitionCount] | None = None,
) -> RepetitionCount:
    """The repetitions of ``seq`` counted apart on either side of each of frames ``cuts``
    (the pose jumped there to another person, :func:`person_jumps`), each piece as a clip of
    its own (by ``count``, default :func:`count_repetitions`: a repetition cut off at a cut
    counts only beside a whole one; a piece shorter than :data:`MIN_PERIOD_S` or showing
    nobody has none), the
    frames numbered in ``seq``. The jump is no movement: counted as one clip, two people's
    postures either side of it read as one going from one to the other. The period (and its
    periodicity) is that of the piece with the most repetitions (the first of those);
    moving: the pieces' angles, first seen first."""
    bounds = [0, *sorted({c for c in cuts if 0 < c < seq.n_frames}), seq.n_frames]
    reps: list[Repetition] = []
    moving: list[str] = []
    partial = alternating = False
    period: tuple[int, float | None, float] = (0, None, 0.0)
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        if (b - a) / seq.fps < MIN_PERIOD_S:
            continue
        piece = dataclasses.replace(seq, positions=seq.positions[a:b], confidence=(
            None if seq.confidence is None else seq.confidence[a:b]
        ))  # fmt: skip
        try:
            found = (count or count_repetitions)(piece)
        except DataError:  # nobody in view in the piece
            continue
        reps += [
            dataclasses.replace(
                r, start_frame=r.start_frame + a, end_frame=r.end_frame + a,
                peak_frame=r.peak_frame + a,
            )
            for r in found.repetitions
        ]  # fmt: skip
        moving += [m for m in found.moving if m not in moving]
        partial |= found.partial
        alternating |= found.alternating and bool(found.repetitions)
        if found.count > period[0]:
            period = (found.count, found.period_s, found.periodicity)
    return RepetitionCount(
        repetitions=tuple(reps),
        fps=seq.fps,
        n_frames=seq.n_frames,
        period_s=period[1],
        periodicity=period[2],
        alternating=alternating,
        moving=tuple(moving),
        partial=partial and not reps,
    )


def count_in_signals(
    sig: MovementSignals,
    n_frames: int,
    fps: float,
    recording_edges: bool | tuple[bool, bool] = True,
    clear_alternation: bool = False,
    settled: tuple[bool, bool] = (False, False),
    past_noise: bool = False,
) -> RepetitionCount:
    """:func:`count_repetitions` on already prepared signals (of a clip of ``n_frames``;
    ``recording_edges`` as there, or a pair: whether the clip's start, and its end, are the
    recording's; a far point cut off at one of those counts only beside a whole one,
    :func:`_whole_only`). ``clear_alternation``: a movement alternates sides only
    as judged about its running mean where the side-against-side movement repeats clearly
    (:data:`CLEAR_PERIODICITY`), as recorded where it does not, for signals that may well
    straddle a change of exercise (segmentation's search for whole periods in fixed spans,
    :func:`cbr.segmentation.periods_in_span`: a twist's last turn and a jog's first steps are
    no period); False, the default: wherever it repeats more than noise would, for a stretch
    of one exercise whose ends may hold a little of the next (:func:`_alternating_repetitions`).
    ``settled``: whether the clip's start, and its end, where they are not the recording's,
    are cuts beyond which nothing turns (the piece of a longer recording beyond shows no far
    point): a posture got into and held still up to such a cut is held on beyond it, and is
    judged as at the recording's end (:func:`_held_change`). ``past_noise``: a first period
    at noise level does not weigh out the angle that moves most (:func:`_periodic_direction`;
    a segment's count, :func:`cbr.segmentation.counted_segments`: not the windows it
    classifies, nor ``reps``)."""
    x = sig.values
    edges = (
        (recording_edges, recording_edges)
        if isinstance(recording_edges, bool)
        else (bool(recording_edges[0]), bool(recording_edges[1]))
    )
    spans, far, direction, sides = _alternating_repetitions(
        x, sig.names, sig.fps, sig.blind, clear_alternation, edges
    )
    partial = False
    alternating = sides is not None
    ends_held = [(False, False)] * len(far)  # an alternating movement's: not judged
    ends_open = ends_held
    period, strength = find_period(np.diff(x, axis=0), sig.fps)
    if sides is None:
        period, strength, direction = _periodic_direction(
            x, period, sig.fps, strength if past_noise else None
        )
        recorded = _movement_line(x, sig.names, direction, sig.fps)
        # a slow change of posture (stepping into place, drifting) is no repetition
        line = _steady(recorded, period, strength, sig.fps)
        clear = period if strength >= CLEAR_PERIODICITY else None
        distance = int(0.5 * (clear or MIN_PERIOD_S) * sig.fps)
        reach = int(period * sig.fps) if period else len(line)
        rest = float(np.percentile(line, 5))
        still = int(round(MIN_PERIOD_S * sig.fps))
        far, back = _far_points(line, rest, distance, reach, still)
        held = not clear_alternation  # not for the windows segmentation classifies
        above = _above_rest(recorded, far, reach, held)
        far, back = far[above], back[above]
        whole = _whole_only(back, edges)
        partial = bool(len(far)) and not whole.any()  # part of one repetition, none whole
        far = np.unique(_in_view(far[whole], sig.blind))
        # far points with the line as recorded held at the far level between them (a squat
        # held at the bottom, whose hold's two ends stand out about the running mean) are one
        # (the posture's direction only where two far points could be one: an SVD saved)
        posture = x * np.abs(movement_direction(x)) if held and len(far) > 1 else None
        groups = (
            _one_hold(recorded, far, reach, posture) if held else [[i] for i in range(len(far))]
        )
        every = far
        far = np.array([_held_peak(recorded, far[g]) for g in groups], dtype=far.dtype)
        # each end judged on its own: a posture got into after a cut and held to the
        # recording's end is no repetition, as one got into after the recording's start
        ends = (edges[0] or settled[0], edges[1] or settled[1])
        if len(far) == 1 and _held_change(x, recorded, sig.fps, int(far[0]), ends):
            far = far[:0]  # got into a posture once and held it: no repetition
        # a lone repetition of a whole recording runs from where the movement leaves rest to
        # where it returns, however far from its far point: one far point repeats nothing, and
        # a period read then (from a wobble, a pose model's flicker) bounds no repetition
        lone = len(far) == 1 and all(edges)
        spans = _bounds(line, every, len(line) if lone else reach, held) if len(far) else []
        spans = [(spans[g[0]][0], spans[g[-1]][1]) for g in groups] if len(far) else []
        ends_held = _held_to_ends(recorded, far)
        ends_open = _held_to_ends(recorded, far, RETURN_SHARE)
    spans = _seen_spans(spans, far, sig.blind)
    reps = [
        Repetition(
            start_frame=int(a * sig.step),
            end_frame=int(min(n_frames, b * sig.step)),
            peak_frame=int(min(n_frames - 1, p * sig.step)),
            side=None if sides is None else str(sides[i]),
            held=ends_held[i],
            unreturned=ends_open[i],
        )
        for i, ((a, b), p) in enumerate(zip(spans, far, strict=True))
    ]
    weights = np.abs(direction)
    order = np.argsort(-weights, kind="stable")
    moving = tuple(sig.names[i] for i in order[:4] if weights[i] > 0.2 * weights.max())
    if _span((x - x.mean(axis=0)) @ direction) < MIN_EXCURSION_RAD:
        moving = ()  # nothing moves as far as a repetition would: jitter names no joint,
        period = None  # nor a period (its autocorrelation peaks somewhere)
    return RepetitionCount(
        tuple(reps), fps, n_frames, period, strength, bool(alternating), moving, partial
    )


def _held_to_ends(
    recorded: np.ndarray, far: np.ndarray, share: float = 0.0
) -> list[tuple[bool, bool]]:
    """Per far point of ``far`` (samples of ``recorded`` ``(n,)``, the movement as recorded),
    whether the line rises to it by less than :data:`MIN_EXCURSION_RAD` from its lowest since
    the clip's start, and falls back from it by less than that to its lowest until the clip's
    end (:attr:`Repetition.held`): a posture held at the far point is a plateau, whose peak
    sample lies anywhere in it. ``share``: by less than that share of the far point's height
    (the larger of the two) where that is more (:attr:`Repetition.unreturned`, at
    :data:`RETURN_SHARE`)."""
    rise = recorded[far] - np.minimum.accumulate(recorded)[far]
    fall = recorded[far] - np.minimum.accumulate(recorded[::-1])[::-1][far]
    short = np.maximum(MIN_EXCURSION_RAD, share * np.maximum(rise, fall))
    return [(bool(r < s), bool(f < s)) for r, f, s in zip(rise, fall, short, strict=True)]


def _periodic_direction(
    x: np.ndarray, period: float | None, fps: float, strength: float | None = None
) -> tuple[float | None, float, np.ndarray]:
    """The period, its autocorrelation and the movement direction ``(C,)`` of ``x`` ``(n, C)``
    with every angle weighted by its periodic energy rather than its variance: its deviations
    scaled by the square root of :func:`periodic_share` at the ``period`` first found, so
    that an angle that jitters (a tracked joint barely moving) or changes once does not pull
    the period or the direction. The direction is mapped back to the angles unweighted, so
    that the movement keeps its size in radians.

    Given the first period's autocorrelation ``strength`` (a segment's count only,
    :func:`count_in_signals`' ``past_noise``), a first period below what noise reaches by
    chance (:func:`_chance_correlation`) tells jitter from movement no better than chance,
    and its shares may weigh out the angle that moves most. Then, when the posture goes out
    and comes back (:func:`_out_and_back`) along the angles' own direction (unweighted,
    :func:`movement_direction`) farther than along the weighted one by at least
    :data:`MIN_EXCURSION_RAD` (the weighting left out as much movement as a repetition
    needs), that direction is the movement's, with the first period: in a ``segment``
    stretch of side-lying leg raises too short for their period to show, the period first
    found (its autocorrelation near 0) gave the raised leg no weight and the arm under the
    head all, and the leg's two raises counted 1 (docs/measurements.md, "Figures behind the
    code's rules: Counting repetitions").
    Out and back, not the range: the arms bent once to start jogging range farther than the
    legs' steps but do not come back; a held side plank's wobble goes about as far either
    way. Not for the windows ``segment`` classifies (:func:`cbr.segmentation.periods_in_span`):
    read so, they moved, and a recording segmented by a case base of the same person's
    others lost a stretch and called the end of another unknown (hunt 37a); nor for ``reps``
    of a whole clip."""
    v = np.diff(x, axis=0)
    w = np.sqrt(periodic_share(v, period, fps))
    weighted = x.mean(axis=0) + (x - x.mean(axis=0)) * w
    found, found_strength = find_period(np.diff(weighted, axis=0), fps)
    d = movement_direction(weighted) * w
    norm = float(np.linalg.norm(d))
    d = d / norm if norm > 0 else movement_direction(x)
    if period is not None and strength is not None and strength < _chance_correlation(len(v)):
        plain = movement_direction(x)
        centred = x - x.mean(axis=0)
        if _out_and_back(centred @ plain) >= _out_and_back(centred @ d) + MIN_EXCURSION_RAD:
            return period, strength, plain
    return found, found_strength, d


def _out_and_back(line: np.ndarray) -> float:
    """How far ``line`` ``(n,)`` goes out and comes back within the clip, either way: at the
    sample where it is greatest, the lesser of its rise from its lowest before and its fall
    to its lowest after (of the line and of its negative). A repetition goes out and comes
    back; a change of posture made once (the arms bent to start jogging) goes out only."""
    best = 0.0
    for signed in (line, -line):
        rise = signed - np.minimum.accumulate(signed)
        fall = signed - np.minimum.accumulate(signed[::-1])[::-1]
        best = max(best, float(np.minimum(rise, fall).max(initial=0.0)))
    return best


def _above_rest(line: np.ndarray, far: np.ndarray, reach: int, held: bool = True) -> np.ndarray:
    """Which far points ``far`` of ``line`` ``(n,)`` (the movement as recorded, before
    :func:`_steady`) rise above the lowest of the line within ``reach`` frames of them by at
    least :data:`STILL_SHARE` of the median such rise: about the running mean, a long still
    stretch between repetitions is a plateau as high above their low points as half a
    repetition, and its middle a far point, though nothing near it moves. Measured near each
    point, so a line that drifts over the clip keeps its shallower repetitions: within
    ``reach`` samples of the far point's hold (:func:`_hold`), so that a far point held for
    longer than two periods (two squats, then a third held 12 s at the bottom and up again)
    is measured from where the line went out to it and came back, not from the hold's own
    level; a still stretch at rest is a hold at its own low level, and stays out. Before,
    the squat held 12 s was taken for rest and not counted. ``held`` False: within ``reach``
    of the far point itself, as before, for the windows segmentation classifies
    (:func:`count_in_signals`' ``clear_alternation``): read so, ``watch``'s windows moved
    and fewer of a streamed recording's blocks came out right (``benchmarks.segment_live``;
    docs/measurements.md, "Figures behind the code's rules: Counting repetitions")."""
    if not len(far):
        return np.zeros(0, dtype=bool)
    height = _rises(line, far, reach, held)
    return np.asarray(height >= STILL_SHARE * float(np.median(height)))


def _one_hold(
    line: np.ndarray, far: np.ndarray, reach: int, posture: np.ndarray | None = None
) -> list[list[int]]:
    """The far points ``far`` (ascending samples of ``line`` ``(n,)``, the movement as
    recorded) grouped into those of one repetition: runs of neighbours between which the line
    does not come back toward rest by :data:`HOLD_SHARE` of the lesser one's rise (above the
    lowest of the line within ``reach`` samples of its hold, as :func:`_above_rest` measures
    it), from the lower of the two. A squat held at the bottom longer than the period is one
    far point as recorded; about the running mean (:func:`_steady`) its hold sags in the
    middle and its two ends stand out as two far points: three squats and a fourth held 2 s
    or more at the bottom and up again counted 5. Measured against the recording's own
    movement, not a fixed angle: a shallow movement's repetitions come back by few degrees.
    Given the ``posture`` ``(n, C)`` the line was read from (weighted, :data:`HOLD_SHARE`),
    neighbours between which the posture does not come back toward rest
    (:func:`_posture_stays_out`, rest the line's lowest since the far point before, or
    ``reach`` samples) are one as well."""
    if not len(far):
        return []
    rise = _rises(line, far, reach)
    groups = [[0]]
    for i in range(1, len(far)):
        p, q = int(far[i - 1]), int(far[i])
        level = min(float(line[p]), float(line[q]))
        dip = level - float(line[p : q + 1].min())
        if dip < HOLD_SHARE * min(float(rise[i - 1]), float(rise[i])) or (
            posture is not None
            and _posture_stays_out(line, posture, p, q, int(far[i - 2]) if i > 1 else p - reach)
        ):
            groups[-1].append(i)
        else:
            groups.append([i])
    return groups


def _posture_stays_out(line: np.ndarray, x: np.ndarray, p: int, q: int, since: int) -> bool:
    """Whether the posture ``x`` ``(n, C)`` does not come back toward rest between the far
    points ``p`` < ``q`` of ``line`` ``(n,)`` (the movement as recorded) by
    :data:`HOLD_SHARE` of the way it went out to either. Rest is the posture the pair left
    from: at the lowest of the line from sample ``since`` (the far point before ``p``, or a
    period before it) to ``p``. Where the line between them falls as low as that, the
    movement came back. Otherwise a far point's excursion is the posture there less rest,
    and the way back at a sample the share of that excursion the posture there no longer
    holds (its projection on the excursion); when no sample between them came back from
    both, the pair is one excursion of the whole posture, however far the line dipped (a
    front kick: the knee bends to lift the leg, straightens half for the kick and bends
    again to bring it back while the hip stays raised; read along the knee alone, two
    repetitions, and a count that wavered as the clip grew).
    ``x`` is weighted as :data:`HOLD_SHARE` says, so that an angle changed once (an arm held
    otherwise in the next take) is no excursion; rest is sought before the pair, not
    anywhere within a period, so that small swings held high before wide ones keep their
    own rest."""
    start = max(0, min(since, p))
    rest_at = start + int(np.argmin(line[start : p + 1]))
    if q - p < 2 or float(line[p + 1 : q].min()) <= float(line[rest_at]):
        return q - p < 2
    rest = x[rest_at]
    between = x[p + 1 : q] - rest
    back = np.ones(len(between))
    for far in (p, q):
        out = x[far] - rest
        size = float(out @ out)
        if size <= 0.0:
            return False
        back = np.minimum(back, 1.0 - between @ out / size)
    return bool(back.max() < HOLD_SHARE)


def _held_peak(line: np.ndarray, far: np.ndarray) -> int:
    """The far point of a group of far points ``far`` (ascending samples of ``line`` ``(n,)``,
    the movement as recorded) that are one (:func:`_one_hold`): where the line is highest from
    the first to the last (in a hold, its first sample at the hold's level), the one far point
    of a group of one."""
    a, b = int(far[0]), int(far[-1])
    return a + int(np.argmax(line[a : b + 1]))


def _rises(line: np.ndarray, far: np.ndarray, reach: int, held: bool = True) -> np.ndarray:
    """How far ``line`` ``(n,)`` rises to each far point of ``far`` from its lowest within
    ``reach`` samples of the far point's hold (:func:`_hold`; of the far point itself when not
    ``held``): :func:`_above_rest`'s measure."""
    reach = max(1, reach)
    lowest = np.empty(len(far))
    for i, p in enumerate(far):
        a, b = _hold(line, int(p)) if held else (int(p), int(p))
        lowest[i] = line[max(0, a - reach) : b + reach + 1].min()
    return np.asarray(line[far] - lowest)


def _hold(line: np.ndarray, peak: int) -> tuple[int, int]:
    """The samples [first, last] around ``peak`` of ``line`` ``(n,)`` over which the line stays
    within :data:`MIN_EXCURSION_RAD` of its value at ``peak``: a posture held there (the
    peak sample alone when the line leaves it at once)."""
    near = np.abs(line - line[peak]) < MIN_EXCURSION_RAD
    left = np.flatnonzero(~near[:peak])
    right = np.flatnonzero(~near[peak + 1 :])
    first = int(left[-1]) + 1 if len(left) else 0
    last = peak + int(right[0]) if len(right) else len(line) - 1
    return first, last


def _steady(line: np.ndarray, period: float | None, strength: float, fps: float) -> np.ndarray:
    """``line`` ``(n,)`` (or each column of ``(n, C)``) about its running mean over one
    ``period`` when the movement repeats clearly
    (autocorrelation ``strength`` >= :data:`CLEAR_PERIODICITY`): a one-off change of posture
    (bending the arms to start jogging) is no part of what repeats. As it is otherwise."""
    if strength < CLEAR_PERIODICITY:
        return line
    return _about_running_mean(line, period, fps)


def _chance_correlation(n: int) -> float:
    """The autocorrelation that ``n`` samples of noise reach by chance (its 95 % bound,
    2 / sqrt(n)): a period whose autocorrelation is below it repeats nothing; a statistical
    bound, not a value fitted to data."""
    return 2.0 / float(np.sqrt(max(1, n)))


def _about_running_mean(line: np.ndarray, period: float | None, fps: float) -> np.ndarray:
    """``line`` ``(n,)`` (or each column of ``(n, C)``) about its running mean over one
    ``period`` (as it is without a period): what changes slower than the period, once, is
    taken out."""
    if period is None:
        return line
    size = max(1, int(period * fps))
    from scipy.ndimage import uniform_filter1d

    return np.asarray(line - uniform_filter1d(line, size, axis=0, mode="nearest"))


def _both_sides_move(spans: np.ndarray, names: tuple[str, ...]) -> bool:
    """Whether the left and the right limbs move about equally (within a factor of two, as
    for the reach of the two sides): the summed robust spans ``(C,)`` of the left angles
    against those of the right. The trunk's angles belong to both sides. False when no
    limb's angle is there (``names`` holds only twins: :func:`_twinned`): the sides have
    nothing to be compared by, and an alternation not shown is not claimed (the left knee
    unseen in a side view that never shows the right arm left only a pose model's wobble of
    the trunk's twist, 25 degrees, to alternate: one lunge counted 5; a twist with no limb
    seen on both sides now counts the turns to one side only, the smaller error)."""
    if not any(n.startswith(("left_", "right_")) for n in names):
        return False
    left = sum(s for s, n in zip(spans, names, strict=True) if not n.startswith("right_"))
    right = sum(s for s, n in zip(spans, names, strict=True) if not n.startswith("left_"))
    return bool(min(left, right) >= 0.5 * max(left, right))


def _limbs_alike(spans: np.ndarray, names: tuple[str, ...], direction: np.ndarray) -> bool:
    """Whether the limbs that carry the side-against-side movement ``direction`` ``(C,)`` move
    about equally on the left and on the right (within a factor of two): the robust spans
    ``(C,)`` of the left limbs' angles, each weighted by its share of the direction, against
    the right limbs'. Where the trunk carries more of the movement than the limbs (a twist),
    the limbs do not decide. A one-legged kick whose arms swing to balance moves both sides
    about equally in all (:func:`_both_sides_move`), but its legs not."""
    spans = spans * np.abs(direction)
    left = sum(s for s, n in zip(spans, names, strict=True) if n.startswith("left_"))
    right = sum(s for s, n in zip(spans, names, strict=True) if n.startswith("right_"))
    trunk = float(spans.sum()) - left - right
    return bool(left + right <= trunk or min(left, right) >= 0.5 * max(left, right))


def _sides_mirror(
    anti: np.ndarray, period: float | None, fps: float, one: np.ndarray, other: np.ndarray
) -> bool:
    """Whether the side-against-side postures ``anti`` ``(n, C)`` at one side's far points
    ``one`` and at the other's ``other`` (samples) are the same movement mirrored: about their
    running mean over one ``period`` (None: nothing repeats, as recorded), their means
    opposed by more than :data:`ALTERNATION_MIN`
    in cosine (a knee raised on the left, then the same knee raise on the right: -1; a kick of
    one leg answered by the other arm swinging: about 0), and as recorded (about the symmetric
    posture) opposed at all (cosine below 0).

    About the running mean, however clearly the movement repeats: a one-off change of
    posture is not what repeats (bending the arms once to start jogging; the end of a twist
    before a jog, in a stretch that starts a little early: that bit of twist lowered the
    autocorrelation below :data:`CLEAR_PERIODICITY`, where the running mean used to be
    dropped, and as recorded the steps' postures were opposed by a cosine just short of
    -0.5: the steps counted as repetitions of one side, too few and not alternating). As
    recorded as well: about
    its running mean any movement that goes out and back is opposed to itself (a one-arm
    raise: up against down), as recorded a raised arm and the arm at rest are not (cosine
    above 0), while a person who stands a little turned leaves a jog's steps opposed, if less.
    Below 0 is "opposed at all", not a value fitted to data: on the repetition benchmark's
    training subjects any bound near 0 counts the same (docs/measurements.md, "Figures behind
    the code's rules: Counting repetitions")."""

    def cosine(a: np.ndarray, b: np.ndarray) -> float:
        norm = float(np.linalg.norm(a) * np.linalg.norm(b))
        return float(a @ b) / norm if norm > 0 else 1.0

    steady = _about_running_mean(anti, period, fps)
    about_mean = cosine(steady[one].mean(axis=0), steady[other].mean(axis=0))
    recorded = cosine(anti[one].mean(axis=0), anti[other].mean(axis=0))
    return about_mean <= -ALTERNATION_MIN and recorded < 0.0


OTHER_SIDE = {"left": "right", "right": "left"}


def _twinned(names: tuple[str, ...]) -> np.ndarray:
    """``(len(names),)`` True where an angle's left-right mirror twin is among ``names`` (the
    trunk's angles and the hips' height are their own twins). An angle whose twin is missing
    (its joint unseen throughout: the left knee, and with it the left knee and hip angles)
    has nothing to be compared with on the other side."""
    present = set(names)
    return np.array([_swap(n) in present for n in names])


def _taking_turns(reach: np.ndarray, sides: np.ndarray, whole: np.ndarray) -> np.ndarray:
    """Which far points of a movement that alternates sides count, of how far each goes out
    from the symmetric posture ``reach`` ``(k,)`` and to which side ``sides`` ``(k,)`` (in
    time order), ``whole`` ``(k,)`` where the line rises to it and falls back from it within
    the clip (:func:`_candidates`): all but the small ones whose sides take turns without
    them. Small: reaching less than half as far (the factor of two the two sides' reaches are
    compared by) as

    - a far point of its own side next to it (no far point of the other side between them):
      the same excursion going out twice;
    - or, for two next to each other, one to each side, the far points before and after
      them: a wobble about the symmetric posture between two repetitions (a side lunge's
      trailing knee bending a little as the person stands back up, 0.15-0.3 rad each way
      between lunges of 0.7-1.4 rad).

    A small far point alone between two of the other side stays, as do the first and the
    last: the sides take turns with it (a jog's fading steps, a third as far as the
    others). Dropped the smallest first: in each round every one (or pair) that no smaller
    one within two far points of it would change. A far point cut off at the clip's start or
    end shows no whole repetition to be measured against: the end of a twist before a jog,
    three times as far as the steps, leaves its first step whole."""
    from scipy.ndimage import minimum_filter1d

    beside = np.where(whole, reach, 0.0)  # how far a neighbour goes out, as measured against
    kept = np.arange(len(reach))
    while len(kept) >= 2:
        r, b, s = reach[kept], beside[kept], sides[kept]
        n = len(kept)
        same = s[1:] == s[:-1]  # (n - 1,) no turn between a far point and the next
        single = np.zeros(n, dtype=bool)
        single[1:] |= same & (r[1:] < 0.5 * b[:-1])
        single[:-1] |= same & (r[:-1] < 0.5 * b[1:])
        pair = np.zeros(n, dtype=bool)  # the far point and the next, between the two around
        top = np.full(n, np.inf)
        if n >= 4:
            top[1:-2] = np.maximum(r[1:-2], r[2:-1])
            pair[1:-2] = ~same[1:-1] & (top[1:-2] < 0.5 * np.minimum(b[:-3], b[3:]))
        score = np.concatenate([np.where(single, r, np.inf), np.where(pair, top, np.inf)])
        if not np.isfinite(score).any():
            break
        rank = np.empty(2 * n)
        rank[np.lexsort((np.tile(np.arange(n), 2), score))] = np.arange(2 * n)
        rank[~np.isfinite(score)] = np.inf
        first = np.minimum(rank[:n], rank[n:])  # the smallest starting at each far point
        near = minimum_filter1d(first, size=5, mode="constant", cval=np.inf)
        go_single = single & (rank[:n] == near)
        go_pair = pair & (rank[n:] == near)
        drop = go_single | go_pair
        drop[1:] |= go_pair[:-1]
        kept = kept[~drop]
    return np.asarray(np.isin(np.arange(len(reach)), kept))


def _one_side_out(
    line: np.ndarray, posture: np.ndarray, far: np.ndarray, sides: np.ndarray, reach: int
) -> list[list[int]]:
    """The far points ``far`` (ascending samples of ``line`` ``(n,)``, how far the movement of
    one side against the other goes out from the symmetric posture) of an alternating
    movement, on sides ``sides``, grouped into those of one excursion: runs of neighbours of
    the same side between which the ``posture`` ``(n, C)`` does not come back toward rest
    (:func:`_posture_stays_out`, rest the symmetric posture the pair left from, sought from
    the far point before them, or ``reach`` samples before). A side lunge's knees shifting at
    the bottom of one lunge move the side-against-side line back by half and out again, while
    the hips stay down: two far points of one side, one repetition."""
    groups: list[list[int]] = [[0]] if len(far) else []
    for i in range(1, len(far)):
        p, q = int(far[i - 1]), int(far[i])
        since = int(far[i - 2]) if i > 1 else p - reach
        if sides[i] == sides[i - 1] and _posture_stays_out(line, posture, p, q, since):
            groups[-1].append(i)
        else:
            groups.append([i])
    return groups


def _side_direction(anti: np.ndarray) -> np.ndarray:
    """The unit direction ``(C,)`` one side moves against the other along, of the
    side-against-side deviations ``anti`` ``(n, C)`` (:func:`side_parts`): as
    :func:`movement_direction`, each angle weighted by how little of the time it is held off
    the symmetric posture (one less its median distance from it over its 95th percentile: a
    kick's hip goes out and comes back; a guard stance's bent arms stay off to one side and
    flip with the kicking leg, a step at each take that pulls the unweighted direction), and
    mapped back unweighted, when the body moves along it at least as far (:func:`_span`) and
    goes out and comes back along it at least as far (:func:`_out_and_back`) as along the
    unweighted direction: the flip of a held posture moves less than the excursion it hides.
    Where it moves less, the weighting has turned the line onto a lesser movement (the legs
    shifting under arms that are held out through a slow extension, and so weighed out
    themselves); where it goes out farther only, onto a change made once (the arms lowered
    from the exercise before, or bent to start a jog); the unweighted direction stands."""
    plain = movement_direction(anti)
    held = np.median(np.abs(anti), axis=0)
    reach = np.percentile(np.abs(anti), 95, axis=0)
    w = np.clip(1.0 - held / np.where(reach > 0, reach, 1.0), 0.0, 1.0)
    weighted = movement_direction(anti * w) * w
    norm = float(np.linalg.norm(weighted))
    if norm == 0:
        return plain
    weighted = weighted / norm
    one, other = anti @ weighted, anti @ plain
    if _span(one) < _span(other) or _out_and_back(one) < _out_and_back(other):
        return plain
    return np.asarray(weighted)


def _alternating_repetitions(
    x: np.ndarray,
    names: tuple[str, ...],
    fps: float,
    blind: np.ndarray | None = None,
    clear_alternation: bool = False,
    edges: tuple[bool, bool] = (True, True),
) -> tuple[list[tuple[int, int]], np.ndarray, np.ndarray, np.ndarray | None]:
    """Repetitions of a movement that alternates sides: what one side does against the other
    spans at least half as much as what both do alike (a knee raise: as much), and the body
    goes out to both sides about equally far. Returns spans, far points, the movement
    direction and the side of each far point (:func:`_sides`); None when the movement does
    not alternate (and the rest empty). ``blind``: the samples where nobody is seen
    (:func:`_in_view`); ``clear_alternation`` as for :func:`count_in_signals`; ``edges``:
    whether the clip's start and its end are the recording's (:func:`_whole_only`).

    An angle whose mirror twin is not among ``names`` (its joint never seen) is its own twin
    in :func:`side_parts`: all its movement counts with what both sides do alike, none with
    what one does against the other, as it is not shown to; the two sides' limbs are compared
    (and the side of each far point told) on the angles whose twins are there
    (:func:`_twinned`)."""
    sym, anti = side_parts(x, names)
    none: tuple[list[tuple[int, int]], np.ndarray, np.ndarray, np.ndarray | None] = (
        [],
        np.array([], dtype=np.int64),
        np.zeros(x.shape[1]),
        None,
    )
    direction = _side_direction(anti)
    line = anti @ direction  # 0 = a symmetric posture
    alike = sym @ movement_direction(sym)
    period, strength = find_period(np.diff(line)[:, None], fps)
    # what repeats, about the running mean over a period, whether or not the movement
    # repeats clearly (a stretch that starts in the exercise before, the arms lowering from a
    # twist into a jog, repeats less clearly, and that one-off change must not pass for what
    # both sides do alike), but not over a "period" that repeats no more than noise would (a
    # squat stretch ending in three jogging steps: its squats, slower, are no one-off change)
    least = CLEAR_PERIODICITY if clear_alternation else _chance_correlation(len(line) - 1)
    repeating = period if strength >= least else None
    if _span(_about_running_mean(line, repeating, fps)) < 0.5 * _span(
        _about_running_mean(alike, repeating, fps)
    ):
        return none  # mostly both sides alike (a squat, a jumping jack)
    # left against right only where both are seen: an angle whose twin is missing throughout
    # (its joint unseen) is no limb standing by, nor one leading
    both = _twinned(names)
    twins = tuple(n for n, b in zip(names, both, strict=True) if b)
    extent = np.percentile(x[:, both], 95, axis=0) - np.percentile(x[:, both], 5, axis=0)
    if not _both_sides_move(extent, twins) or not _limbs_alike(extent, twins, direction[both]):
        return none  # one limb moves, the other stands by (a kick, a one-arm raise)
    # a full period holds one repetition per side
    distance = int(0.25 * (period or 2 * MIN_PERIOD_S) * fps)
    # far points on each side of the symmetric posture; a posture held off to one side (a
    # lunge's split stance, lying on one side) does not alternate
    one, one_back = _candidates(line, 0.0, distance)
    other, other_back = _candidates(-line, 0.0, distance)
    out_one, out_other = _beyond(line, one), _beyond(-line, other)
    one, one_back, other, other_back = (
        one[out_one],
        one_back[out_one],
        other[out_other],
        other_back[out_other],
    )
    keep_one = _reached(line[one], one_back)
    keep_other = _reached(-line[other], other_back)
    one, one_back, other, other_back = (
        one[keep_one],
        one_back[keep_one],
        other[keep_other],
        other_back[keep_other],
    )
    if not len(one) or not len(other):
        return none  # one side only: counted as a plain movement
    if not _sides_mirror(anti, repeating, fps, one, other):
        return none  # each side's excursion moves other limbs (a kick, an arm swung to balance)
    reach_one = float(np.median(line[one]))
    reach_other = float(np.median(-line[other]))
    if min(reach_one, reach_other) < 0.5 * max(reach_one, reach_other):
        return none  # one side goes out far, the other barely: not alternating
    first = _sides(x[:, both], twins, one, other, direction[both])
    far = np.concatenate([one, other])
    sides = np.array([first] * len(one) + [OTHER_SIDE[first]] * len(other))
    # and a far point cut off at the clip's start or end, against the whole ones of both
    # sides (a side whose only far point is cut off had none of its own: a single twist
    # that turns back as the clip ends)
    back = np.concatenate([one_back, other_back])
    reached = _reached(np.abs(line[far]), back)
    reached[reached] = _whole_only(back[reached], edges)
    order = np.argsort(far[reached], kind="stable")
    far, sides = far[reached][order], sides[reached][order]
    back = back[reached][order]
    whole = ~(back < MIN_EXCURSION_RAD).any(axis=1)
    turns = _taking_turns(np.abs(line[far]), sides, whole)
    far, sides, back = far[turns], sides[turns], back[turns]
    # one side's far points the whole posture does not come back toward rest between are
    # one excursion (a side lunge whose knees shift at the bottom)
    cycle = int(period * fps) if period else len(line)
    groups = _one_side_out(np.abs(line), x * np.abs(movement_direction(x)), far, sides, cycle)
    peak = [g[int(np.argmax(np.abs(line[far[g]])))] for g in groups]
    back = np.array([[back[g[0], 0], back[g[-1], 1]] for g in groups]).reshape(-1, 2)
    far, sides = far[peak], sides[peak]
    # a far point cut off at the clip's start or end against the whole repetitions left, not
    # the wobbles taken out (whose median let a wobble cut off at the end count)
    kept = _reached(np.abs(line[far]), back)
    far, sides = far[kept], sides[kept]
    moved = _in_view(far, blind)
    once = np.diff(moved, prepend=-1) > 0  # two far points moved onto one sample: one
    far, sides = moved[once], sides[once]
    if not len(far):
        return none
    reach = int(0.5 * period * fps) if period else len(line)
    return _bounds(np.abs(line), far, reach), far, direction, sides


__all__ = [
    "ALTERNATION_MIN",
    "AT_EASE",
    "EASE_SHARE",
    "ENDS_S",
    "LEAVE_SHARE",
    "MIN_EXCURSION_RAD",
    "MIN_PERIOD_S",
    "RETURN_SHARE",
    "STILL_SHARE",
    "SUBSTANTIAL",
    "TRUNK_SIDE_SHARE",
    "MovementSignals",
    "Repetition",
    "RepetitionCount",
    "Split",
    "WINDOW_HOP_S",
    "WINDOW_S",
    "split_repetitions",
    "case_spans",
    "split_windows",
    "SPLITS",
    "Cut",
    "cut_clips",
    "long_enough",
    "TWIST_NAMES",
    "upper_arm_turn",
    "PELVIS_HEIGHT",
    "pelvis_height",
    "periodic_share",
    "mirror_matrix",
    "movement_direction",
    "side_parts",
    "autocorrelation",
    "count_in_signals",
    "count_repetitions",
    "counted_angles",
    "find_period",
    "mirror_angles",
    "movement_signals",
    "glitch_free_fps",
    "median_width",
]


@dataclass(frozen=True)
class Split:
    """Clips cut into their repetitions (or windows): the new clips, and how many of the
    originals had no repetition (or were too short for one) and stayed whole; ``cycles``:
    how many of the new clips are left-and-right cycles of a movement that alternates sides
    (:func:`case_spans`), two turns or more, not one repetition."""

    clips: list[Clip]
    kept_whole: int
    cycles: int = 0


def split_repetitions(clips: Sequence[Clip]) -> Split:
    """Every clip cut into its repetitions (:func:`count_repetitions`), those of a movement
    that alternates sides in turns too short alone (a jog's steps) in whole left-and-right
    cycles (:func:`case_spans`), each a clip of
    its own with the clip's label, subject and extras (plus ``repetition``: 1, 2, ..., the
    piece's place in the clip); the frames and what was computed for them are shared with
    the clip (:func:`features.derived.stretch`). A clip without a repetition stays whole."""
    out: list[Clip] = []
    whole = cycles = 0
    for clip in clips:
        try:
            count: RepetitionCount | None = count_repetitions(clip.seq)
        except DataError:
            count = None
        spans = case_spans(count) if count is not None else []
        if not spans:
            out.append(clip)
            whole += 1
            continue
        cycles += sum(turns > 1 for _, _, turns in spans)
        for k, (a, b, _) in enumerate(spans, start=1):
            part = stretch(clip.seq, a, b).with_metadata(repetition=k)
            out.append(dataclasses.replace(clip, seq=part, extras={**clip.extras, "repetition": k}))
    return Split(out, whole, cycles)


def case_spans(count: RepetitionCount) -> list[tuple[int, int, int]]:
    """The pieces ``train --split repetitions`` makes of a clip counted ``count``: frames
    ``[start, end)`` and how many repetitions each holds. One per repetition; but a movement
    that alternates sides (one repetition per side's turn) whose turns are shorter than one
    repetition can be (their median under :data:`MIN_PERIOD_S`: a jog's steps, 0.3-0.4 s)
    is cut in whole left-and-right cycles, a turn and the next together: the shortest period
    bounds the movement's full cycle, not one side's half of it, and a single step could be
    no case (nor a clip ``classify`` takes). Turns pair in order where one ends as the next
    begins (not across a stretch that shows nobody, :func:`_seen_spans`); a turn left over
    at the end of such a run is a piece of its own when it lasts :data:`MIN_PERIOD_S` or
    more, else joined to the cycle before it (a run of one turn stays one piece, however
    short). Slower alternating movements (knee raises, twists: turns of 1-2 s) keep a case
    per turn, each a whole excursion and back, as ``reps`` counts them."""
    reps = [(r.start_frame, r.end_frame) for r in count.repetitions]
    shortest = MIN_PERIOD_S * count.fps
    if not (count.alternating and reps) or np.median([b - a for a, b in reps]) >= shortest:
        return [(a, b, 1) for a, b in reps]
    runs: list[list[tuple[int, int]]] = []
    for a, b in reps:
        if runs and runs[-1][-1][1] == a:
            runs[-1].append((a, b))
        else:
            runs.append([(a, b)])
    out: list[tuple[int, int, int]] = []
    for run in runs:
        pieces = [(run[i][0], run[min(i + 1, len(run) - 1)][1], len(run[i : i + 2]))
                  for i in range(0, len(run), 2)]  # fmt: skip
        last = pieces[-1]
        if len(pieces) > 1 and last[2] == 1 and last[1] - last[0] < shortest:
            before = pieces[-2]
            pieces[-2:] = [(before[0], last[1], before[2] + 1)]
        out += pieces
    return out


WINDOW_S = 2.0
"""The length of the windows :func:`split_windows` cuts, the windows ``posecbr segment``
classifies (cases and queries cut alike lie at comparable distances)."""
WINDOW_HOP_S = 0.5
"""A window starts every this many seconds."""


def split_windows(
    clips: Sequence[Clip], length_s: float = WINDOW_S, hop_s: float = WINDOW_HOP_S
) -> Split:
    """Every clip cut into windows of ``length_s`` seconds starting every ``hop_s`` seconds
    (as many as fit whole), each a clip of its own with the clip's label, subject and extras
    (plus ``window``: 1, 2, ...); frames and per-frame results are shared with the clip
    (:func:`features.derived.stretch`). Window k starts at frame k x ``hop_s`` x fps rounded
    (a hop rounded once would drift: 12 frames at 25 fps, a window every 0.48 s). A clip
    shorter than one window stays whole.

    A case base of windows is what segmenting a long recording matches its windows against:
    every phase of a repeated movement is among the cases, as it is among the queries."""
    out: list[Clip] = []
    whole = 0
    for clip in clips:
        fps = clip.seq.fps
        length = int(round(length_s * fps))
        starts = _window_starts(clip.seq.n_frames, length, hop_s * fps)
        if length < 2 or not len(starts):
            out.append(clip)
            whole += 1
            continue
        for k, a in enumerate(starts, start=1):
            part = stretch(clip.seq, a, a + length).with_metadata(window=k)
            out.append(dataclasses.replace(clip, seq=part, extras={**clip.extras, "window": k}))
    return Split(out, whole)


def _window_starts(n_frames: int, length: int, hop: float) -> list[int]:
    """The first frames of the windows of ``length`` frames that fit whole in ``n_frames``,
    one every ``hop`` frames (a fraction: each start rounded on its own), none twice."""
    if n_frames < length:
        return []
    count = int(np.floor((n_frames - length) / hop + 1e-9)) + 1
    return sorted({int(round(k * hop)) for k in range(count)})


SPLITS = ("clips", "repetitions", "windows")
"""What a training clip can be cut into (``posecbr train --split``): kept whole, its
repetitions (:func:`split_repetitions`) or its windows (:func:`split_windows`)."""


@dataclass(frozen=True)
class Cut:
    """Clips cut as ``posecbr train --split`` cuts them (:func:`cut_clips`): the cases' clips,
    and the clips given that stayed whole (no repetition found, or shorter than a window);
    ``cycles``: how many cases are left-and-right cycles (:attr:`Split.cycles`)."""

    clips: list[Clip]
    kept_whole: list[Clip]
    cycles: int = 0


def cut_clips(clips: Sequence[Clip], split: str) -> Cut:
    """Every clip cut into ``split`` (one of :data:`SPLITS`): ``"clips"`` keeps each whole,
    ``"repetitions"`` cuts it into its repetitions (a jog's steps, too short alone, into whole
    left-and-right cycles, :func:`case_spans`), ``"windows"`` into the 2-s windows every
    0.5 s that ``posecbr segment`` and ``watch`` classify. The one cutting ``posecbr train
    --split`` and :func:`cbr.training.cut` do."""
    if split == "clips":
        return Cut(list(clips), [])
    if split == "repetitions":
        cut = split_repetitions(clips)
    elif split == "windows":
        cut = split_windows(clips)
    else:
        raise ValueError(f"split must be one of {', '.join(map(repr, SPLITS))}, got {split!r}")
    given = {id(c) for c in clips}  # a clip kept whole is passed on as it came
    return Cut(cut.clips, [c for c in cut.clips if id(c) in given], cut.cycles)


def long_enough(clips: Sequence[Clip]) -> tuple[list[Clip], list[Clip]]:
    """The labelled stretches of recordings labelled over time that last at least the
    shortest repetition (:data:`MIN_PERIOD_S`), and the others: a label that flickers for a
    few frames would each become a case of next to nothing (one frame labelled otherwise:
    an activity of one one-frame case). ``posecbr train`` and
    :func:`cbr.training.cut_recording` leave those out."""
    ok = [c.seq.n_frames >= MIN_PERIOD_S * c.seq.fps for c in clips]
    return (
        [c for c, keep in zip(clips, ok, strict=True) if keep],
        [c for c, keep in zip(clips, ok, strict=True) if not keep],
    )
