"""Compiled (numba) kernels of the fluent engine: same results as the numpy reference.

:func:`fluent_confidences` computes every state of every fluent for every frame in one pass
over ``(frames, fluents)`` and writes straight into the ``(frames, n_states)`` output. It is
the numpy reference in :mod:`features.fluents` (``evaluate(..., backend="numpy")``), fused:

- the logistic (paper eqs. 2-3) calls ``exp`` only inside the band τ±δ; outside it is 0 or 1;
- the temporal product (eq. 5) ``∏ C_a^(1/(a+1))`` is decided without any transcendental when
  a defined factor is NaN (-> NaN) or 0 (-> 0), which is the common case for a still joint
  (noise makes Δθ change sign); otherwise it is ``exp(Σ log C_a / (a+1))``;
- for an integer lag (the source rate a multiple of the reference rate: 30, 60, 120 Hz) the Δ
  of age ``a`` at frame ``f`` is the newest Δ of frame ``f - a·lag``, so ``log C`` of each Δ
  is computed at most once and reused by the ``window`` frames that see it (a ring buffer);
  a fractional lag interpolates like the reference and recomputes.

Numerics: the reference multiplies powers, this sums logarithms; they agree to ~1e-15.

:func:`state_signal_values` is :func:`features.signals.state_signals` in one pass over the
frames (body frame, 22 angles, near distances), repeating the reference's float operations.

Compiled with ``cache=True`` so only the first run on a machine pays the compile time. Hot
loops are written inline rather than as helpers taking arrays: every such call costs atomic
reference-count updates, which made the per-fluent helpers the bottleneck.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# Output column codes (one per state column), shared with features.fluents.
LO, MID, HI, TWO_HI, TOUCH, M_LO, M_HI, STILL = range(8)


@njit(cache=True, nogil=True, inline="always")
def _lower(x: float, lo_edge: float, hi_edge: float, tau: float, k: float) -> float:
    """Paper eq. 2 for one value: 1 below the band, 0 above, logistic inside, NaN for NaN."""
    if x < lo_edge:
        return 1.0
    if x > hi_edge:
        return 0.0
    return 1.0 / (1.0 + math.exp(k * (x - tau)))  # NaN stays NaN


@njit(cache=True, nogil=True)
def _log_c(d: float, tau: float, k: float, direction: int) -> float:
    """log C of a Δ inside the band of one direction (0: toward s0, 1: toward sn)."""
    c = 1.0 / (1.0 + math.exp(k * (d - tau)))
    return math.log(c if direction == 0 else 1.0 - c)


@njit(cache=True, nogil=True)
def fluent_confidences(
    values: np.ndarray,
    dist_m: np.ndarray,
    sig_col: np.ndarray,
    dist_col: np.ndarray,
    inst: np.ndarray,
    motion: np.ndarray,
    three: np.ndarray,
    partner: np.ndarray,
    touching_m: float,
    lag: float,
    window: int,
    col_code: np.ndarray,
    col_fluent: np.ndarray,
    col_out: np.ndarray,
    nan_cols: np.ndarray,
    out: np.ndarray,
) -> None:
    """Fill ``out`` ``(frames, n_states)`` with every state's confidence.

    values: ``(frames, n_signals)`` signals; dist_m: ``(frames, n_pairs)`` near distances in
    metres. Per fluent i (n of them): ``sig_col[i]`` its column in ``values``, ``dist_col[i]``
    its column in ``dist_m`` (-1: not a distance fluent); ``inst[i]`` = (lower τ-δ, τ+δ, τ, k,
    upper τ-δ, τ+δ, τ, k) and ``motion[i]`` = (toward-s0 τ-δ, τ+δ, τ, k, toward-sn τ-δ, τ+δ,
    τ, k), k = ln((1-ε)/ε)/δ; ``three[i]``: has an upper boundary; ``partner[i]``: the other
    fluent of a tilt pair (or i). Per computed column j: ``col_code[j]`` (LO..STILL),
    ``col_fluent[j]`` and ``col_out[j]`` its column in ``out``; ``nan_cols``: columns of
    ``out`` to fill with NaN (fluents the caller left out because their signal is missing in
    every frame). ``lag``: source frames per reference interval; ``window``: r.
    """
    frames = values.shape[0]
    n = sig_col.shape[0]
    n_cols = col_code.shape[0]
    blk = np.empty((8, n))
    m_e0, m_e1 = motion[:, 0].copy(), motion[:, 1].copy()  # contiguous band edges
    m_e4, m_e5 = motion[:, 4].copy(), motion[:, 5].copy()
    blk[TOUCH, :] = np.nan  # only near fluents have a touching state
    inv = np.empty(window)
    for a in range(window):
        inv[a] = 1.0 / (a + 1)
    integer_lag = lag >= 1.0 and lag == math.floor(lag)
    step = int(lag) if integer_lag else 0
    # Integer lag: a ring over the last window·lag frames of each fluent's newest Δ and of
    # log C(Δ) per direction: 0 = C is 1 (or no history: counts as 1), -inf = C is 0, NaN,
    # or +1 = inside the band, log not computed yet (logs are <= 0, so +1 cannot be a value).
    # A window's log-sum is then -inf (a zero: product 0) or NaN without any exp/log.
    ring_size = window * step if integer_lag else 1
    ring_d = np.zeros((ring_size, n))
    ring_lc = np.zeros((2, ring_size, n))
    # Fractional lag: interpolation positions of the window + 1 samples of one frame.
    s_lo = np.empty(window + 1, dtype=np.intp)
    s_hi = np.empty(window + 1, dtype=np.intp)
    s_w = np.empty(window + 1)
    s_ok = np.empty(window + 1, dtype=np.bool_)
    slots = np.empty(window, dtype=np.intp)
    totals = np.empty(n)
    pendings = np.empty(n)
    deltas = np.empty(window)
    samples = np.empty(window + 1)
    for f in range(frames):
        if integer_lag:
            slot = f % ring_size
            newest_ok = f - step >= 0
        else:
            for m in range(window + 1):
                pos = f - m * lag
                s_ok[m] = pos >= -1e-9
                pos = min(max(pos, 0.0), frames - 1.0)
                lo = int(math.floor(pos))
                s_lo[m] = lo
                s_hi[m] = min(lo + 1, frames - 1)
                s_w[m] = pos - lo
            newest_ok = s_ok[1]
        for i in range(n):
            x = values[f, sig_col[i]]
            c_lo = _lower(x, inst[i, 0], inst[i, 1], inst[i, 2], inst[i, 3])
            if three[i]:
                c_up = 1.0 - _lower(x, inst[i, 4], inst[i, 5], inst[i, 6], inst[i, 7])
            else:
                c_up = np.nan if x != x else 0.0
            blk[LO, i] = c_lo
            blk[HI, i] = c_up
            blk[TWO_HI, i] = 1.0 - c_lo
            blk[MID, i] = (1.0 - c_lo) * (1.0 - c_up)
            dc = dist_col[i]
            if dc >= 0:
                d = dist_m[f, dc]
                blk[TOUCH, i] = d if d != d else (1.0 if d <= touching_m else 0.0)
        if integer_lag and not newest_ok:
            # No Δ yet: the ring keeps 0 (= factor 1, no evidence) for this frame.
            for i in range(n):
                ring_d[slot, i] = 0.0
                ring_lc[0, slot, i] = 0.0
                ring_lc[1, slot, i] = 0.0
                blk[M_LO, i] = np.nan
                blk[M_HI, i] = np.nan
        elif integer_lag:
            # Eq. 5 with an integer lag: the Δ of age a is the newest Δ of frame f - a·lag.
            # (Inline, not a helper: a call passing arrays costs atomic refcounts per call.)
            for i in range(n):
                sc = sig_col[i]
                ring_d[slot, i] = values[f, sc] - values[f - step, sc]
            for i in range(n):  # selects only: vectorises
                d = ring_d[slot, i]
                # toward s0 (lower state): 1 below the band, 0 above it
                v = 1.0
                v = 0.0 if d < m_e0[i] else v
                v = -np.inf if d > m_e1[i] else v
                ring_lc[0, slot, i] = d if d != d else v
                # toward sn (upper state = 1 - lower): 0 below the band, 1 above it
                v = 1.0
                v = -np.inf if d < m_e4[i] else v
                v = 0.0 if d > m_e5[i] else v
                ring_lc[1, slot, i] = d if d != d else v
            # Slots of the window's ages (age 0 = this frame); frames before 0 hold 0.
            for a in range(window):
                slots[a] = (f - a * step) % ring_size
            for direction in range(2):
                totals[:] = 0.0
                pendings[:] = 0.0
                for a in range(window):
                    sa = slots[a]
                    w = inv[a]
                    for i in range(n):  # branch-free: vectorises
                        v = ring_lc[direction, sa, i]
                        pendings[i] += v > 0.0
                        totals[i] += v * w
                for i in range(n):
                    t = totals[i]
                    # NaN (a NaN factor), -inf (a zero factor) and 0 (all ones) decide the
                    # product without exp or log; only a product strictly between 0 and 1 (a
                    # few % of them) takes the branch, so it is well predicted.
                    slow = (t > -np.inf) & ((t != 0.0) | (pendings[i] > 0.0))
                    if not slow:
                        r = 0.0 if t == -np.inf else (t if t != t else 1.0)
                    elif pendings[i] > 0.0:
                        # Every factor is positive: compute the missing logs, once per Δ.
                        q_tau = motion[i, 4 * direction + 2]
                        q_k = motion[i, 4 * direction + 3]
                        t = 0.0
                        for a in range(window):
                            sa = slots[a]
                            v = ring_lc[direction, sa, i]
                            if v > 0.0:
                                v = _log_c(ring_d[sa, i], q_tau, q_k, direction)
                                ring_lc[direction, sa, i] = v
                            t += v * inv[a]
                        r = math.exp(t)
                    else:
                        r = math.exp(t)
                    blk[M_LO + direction, i] = r
        else:
            for i in range(n):
                if not newest_ok:
                    blk[M_LO, i] = np.nan
                    blk[M_HI, i] = np.nan
                    continue
                sc = sig_col[i]
                for m in range(window + 1):
                    lo = s_lo[m]
                    w = s_w[m]
                    if w == 0.0:
                        samples[m] = values[lo, sc]
                    else:
                        samples[m] = values[lo, sc] * (1.0 - w) + values[s_hi[m], sc] * w
                n_age = 0
                for a in range(window):
                    if not s_ok[a + 1]:
                        break
                    deltas[a] = samples[a] - samples[a + 1]
                    n_age += 1
                for direction in range(2):
                    # eq. 5 from log codes as in _temporal_integer, without the cache
                    off = 4 * direction
                    e0, e1 = motion[i, off], motion[i, off + 1]
                    total = 0.0
                    pending = 0
                    for a in range(n_age):
                        d = deltas[a]
                        # selects, not branches: the side of the band flips with noise
                        v = 1.0
                        v = (0.0 if direction == 0 else -np.inf) if d < e0 else v
                        v = (-np.inf if direction == 0 else 0.0) if d > e1 else v
                        v = d if d != d else v
                        pending += v > 0.0
                        total += v * inv[a]
                    slow = (total > -np.inf) & ((total != 0.0) | (pending > 0))
                    if not slow:  # NaN, a zero factor, or all ones
                        r = 0.0 if total == -np.inf else (total if total != total else 1.0)
                    elif pending == 0:
                        r = math.exp(total)
                    else:
                        total = 0.0
                        for a in range(n_age):
                            d = deltas[a]
                            if e0 <= d <= e1:  # inside the band (zeros returned above)
                                total += _log_c(d, motion[i, off + 2], motion[i, off + 3],
                                                direction) * inv[a]  # fmt: skip
                        r = math.exp(total)
                    blk[M_LO + direction, i] = r
        for i in range(n):
            t_lo = blk[M_LO, i]
            t_hi = blk[M_HI, i]
            blk[STILL, i] = (1.0 - t_lo) * (1.0 - t_hi)
        for i in range(n):
            j = partner[i]
            if j != i:
                # A tilt pair shares "upright" and "tilt steady": both directions must hold.
                blk[MID, i] = blk[MID, i] * ((1.0 - blk[LO, j]) * (1.0 - blk[HI, j]))
                blk[STILL, i] = blk[STILL, i] * ((1.0 - blk[M_LO, j]) * (1.0 - blk[M_HI, j]))
        for j in range(n_cols):
            out[f, col_out[j]] = blk[col_code[j], col_fluent[j]]
        for j in range(nan_cols.shape[0]):
            out[f, nan_cols[j]] = np.nan


# ---------------------------------------------------------------------------------------------
# State signals (features.signals): the body frame, 22 angles and the near distances per frame.
# Each helper repeats the float operations of features.geometry in the same order (cross
# product terms, a·b summed left to right), so the two backends agree to the last bit or two.

Vec = tuple[float, float, float]


@njit(cache=True, nogil=True)
def _get(p: np.ndarray, f: int, j: int) -> Vec:
    return (p[f, j, 0], p[f, j, 1], p[f, j, 2])


@njit(cache=True, nogil=True)
def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True, nogil=True)
def _mid(a: Vec, b: Vec) -> Vec:
    return (0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]))


@njit(cache=True, nogil=True)
def _dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, nogil=True)
def _cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True, nogil=True)
def _unit(v: Vec, min_len: float) -> Vec:
    n = math.sqrt(_dot(v, v))
    if n >= min_len:
        return (v[0] / n, v[1] / n, v[2] / n)
    return (np.nan, np.nan, np.nan)


@njit(cache=True, nogil=True)
def _project(v: Vec, n: Vec) -> Vec:
    d = _dot(v, n)
    return (v[0] - d * n[0], v[1] - d * n[1], v[2] - d * n[2])


@njit(cache=True, nogil=True)
def _angle(u: Vec, v: Vec, min_len: float) -> float:
    nu = math.sqrt(_dot(u, u))
    nv = math.sqrt(_dot(v, v))
    if nu >= min_len and nv >= min_len:
        return math.acos(min(max(_dot(u, v) / (nu * nv), -1.0), 1.0))
    return np.nan


@njit(cache=True, nogil=True)
def state_signal_values(
    p: np.ndarray, joints: np.ndarray, near_a: np.ndarray, near_b: np.ndarray,
    min_len: float, values: np.ndarray, head_length: np.ndarray, dist_m: np.ndarray,
) -> None:  # fmt: skip
    """Fill the signals of :func:`features.signals.state_signals` from canonical positions.

    p: ``(frames, 33, 3)``; joints: canonical indices of (nose, left/right ear, shoulder,
    elbow, wrist, hip, knee, ankle) in that order; near_a/near_b: ``(n_pairs,)`` joint indices.
    Writes values ``(frames, 22 + n_pairs)`` (angles in ANGLE_SIGNALS order, then distances in
    head-lengths), head_length ``(frames,)`` metres and dist_m ``(frames, n_pairs)`` metres.
    """
    up_w = (0.0, 1.0, 0.0)
    n_pairs = near_a.shape[0]
    for f in range(p.shape[0]):
        nose = _get(p, f, joints[0])
        ls, rs = _get(p, f, joints[3]), _get(p, f, joints[4])
        lh, rh = _get(p, f, joints[9]), _get(p, f, joints[10])
        neck = _mid(ls, rs)
        mid_hip = _mid(lh, rh)
        mid_ear = _mid(_get(p, f, joints[1]), _get(p, f, joints[2]))
        forward = _unit(_cross(_sub(rs, ls), _sub(lh, ls)), min_len)
        up = _unit(_sub(neck, mid_hip), min_len)
        left = _unit(_cross(up, forward), min_len)
        level_left = _unit(_project(left, up_w), min_len)
        heading = _unit(_cross(level_left, up_w), min_len)
        for side in range(2):
            sh, el = _get(p, f, joints[3 + side]), _get(p, f, joints[5 + side])
            wr, hip = _get(p, f, joints[7 + side]), _get(p, f, joints[9 + side])
            kn, an = _get(p, f, joints[11 + side]), _get(p, f, joints[13 + side])
            s = 1.0 if side == 0 else -1.0
            outward = (s * left[0], s * left[1], s * left[2])
            arm, leg = _sub(el, sh), _sub(kn, hip)
            values[f, 0 + side] = _angle(_sub(sh, el), _sub(wr, el), min_len)
            values[f, 2 + side] = _angle(_sub(hip, kn), _sub(an, kn), min_len)
            values[f, 4 + side] = _angle(_sub(el, sh), _sub(hip, sh), min_len)
            values[f, 6 + side] = _angle(_sub(kn, hip), _sub(sh, hip), min_len)
            values[f, 8 + side] = _angle(_project(arm, left), forward, min_len)
            values[f, 10 + side] = _angle(_project(leg, left), forward, min_len)
            values[f, 12 + side] = _angle(_project(arm, forward), outward, min_len)
            values[f, 14 + side] = _angle(_project(leg, forward), outward, min_len)
        head = _sub(mid_ear, neck)
        torso = _sub(neck, mid_hip)
        values[f, 16] = _angle(_project(head, left), forward, min_len)
        values[f, 17] = _angle(_project(head, forward), left, min_len)
        values[f, 18] = _angle(_project(torso, level_left), heading, min_len)
        values[f, 19] = _angle(_project(torso, heading), level_left, min_len)
        values[f, 20] = _angle(
            _project(_sub(nose, neck), up), _project(_sub(ls, neck), up), min_len
        )
        values[f, 21] = _angle(_project(_sub(lh, mid_hip), up), _project(forward, up), min_len)
        e = _sub(mid_ear, neck)
        hl = 2.0 * math.sqrt(_dot(e, e))
        if not hl > 0.0:
            hl = np.nan
        head_length[f] = hl
        for k in range(n_pairs):
            d = _sub(_get(p, f, near_a[k]), _get(p, f, near_b[k]))
            dm = math.sqrt(_dot(d, d))
            dist_m[f, k] = dm
            values[f, 22 + k] = dm / hl
