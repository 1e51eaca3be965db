"""Compiled (numba) kernels of the fluent engine: the numpy reference's results, fast.

:func:`fluent_columns` computes every state of every fluent for every frame and writes the
``(n_states, frames)`` transpose of the result (float32; ``features.fluents.evaluate`` returns
its ``.T``, a column-major ``(frames, n_states)``). It is the numpy reference in
:mod:`features.fluents` (``evaluate(..., backend="numpy")``) reorganised so that the loops
vectorise:

- the loops run over the frames of a block (512) for one fluent at a time: each block's
  signals are first copied into per-fluent series (from row-major ``(frames, n)`` arrays),
  each state's series is written contiguously out, every buffer in L1;
- branch-free: a value outside its band gets the logistic argument -inf or +inf (confidence
  exactly 1 or 0), so one formula serves every frame; the band decisions and the differences
  beside a threshold (x - τ, Δθ) stay float64, as in the reference, the rest is float32;
- ``exp`` and ``log1p`` are polynomials written here (no library call, which would keep a
  loop scalar); relative error < 1e-7;
- eq. 5 is a weighted sum of logs: ``∏ C_a^(1/(a+1)) = exp(Σ log C_a / (a+1))``. For an
  integer lag (a source rate that is a multiple of the reference rate: 30, 60, 120 Hz) the Δ
  of age ``a`` at frame ``f`` is the newest Δ of frame ``f - a·lag``, so ``log C`` of each Δ
  is computed once and the window is a sum of shifted series; a fractional lag interpolates
  like the reference and computes each Δ of each frame;
- with the default motion band (τ >= δ: the two directions' bands meet at most at Δ = 0) one
  logistic and one exp serve both directions of motion.

Numerics: the confidences agree with the float64 reference to ~3e-7 (tested at 1e-6), with
the same NaN, the same exact 0 and the same exact 1.

:func:`state_signal_values` is :func:`features.signals.state_signals` in one pass over the
frames (body frame, 22 angles, near distances), repeating the reference's float operations.

Compiled with ``cache=True`` so only the first run on a machine pays the compile time. The
helpers are compiled on their own and left to LLVM to inline: numba's IR inlining of every
helper into the kernel (``inline="always"``) doubled its compile time (34 s -> 18 s of CPU
without it, cold) for the same speed and the same confidences bit for bit.
"""

from __future__ import annotations

import errno
import math
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

_Fn = TypeVar("_Fn", bound=Callable[..., Any])


#: What a write of numba's on-disk cache may fail with where there is no room for it: a full
#: disk, a quota used up, a file size limit (``ulimit -f``).
_NO_ROOM = frozenset({errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC), errno.EFBIG})


def _compiled(**options: Any) -> Callable[[_Fn], _Fn]:
    """``numba.njit(**options)``, typed: numba's decorators carry no type hints, and the
    compiled function takes and returns what the Python function declares.

    With ``cache=True`` a compiled function that finds no room to save itself to numba's
    on-disk cache is used all the same, unsaved (compiled again by the next run): the cache
    only saves the next run's compile time, and a write failing past ``ulimit -f`` ended a
    command that writes no file of its own with "cannot write ... File too large". numba
    writes each cache file to a temporary and renames it, so a write cut short leaves no
    cache file behind."""
    jit: Any = njit
    decorator: Callable[[_Fn], _Fn] = jit(**options)
    if not options.get("cache"):
        return decorator

    def compiled(function: _Fn) -> _Fn:
        dispatcher: Any = decorator(function)
        _unsaved_without_room(dispatcher._cache)
        result: _Fn = dispatcher
        return result

    return compiled


def _unsaved_without_room(cache: Any) -> None:
    """Make ``cache`` (a numba dispatcher's ``FunctionCache``) skip a save that finds no room."""
    save = cache.save_overload

    def save_overload(signature: Any, data: Any) -> None:
        try:
            save(signature, data)
        except OSError as error:
            if error.errno not in _NO_ROOM:
                raise

    cache.save_overload = save_overload


_Codegen = Callable[[Any, Any, Any, Any], Any]


def _intrinsic(fn: Callable[..., tuple[Any, _Codegen]]) -> Callable[..., Any]:
    """``numba.extending.intrinsic``, typed: compiled code calls the result with the
    arguments that follow the typing context."""
    wrap: Any = intrinsic
    compiled: Callable[..., Any] = wrap(fn)
    return compiled


# Output column codes (the blocks a state column comes from), shared with features.fluents.
LO, MID, HI, TWO_HI, TOUCH, M_LO, M_HI, STILL = range(8)

# Frames per block: every per-fluent buffer of a block (a few kB each) stays in L1.
BLOCK = 512

# Only the float contractions (FMA) of fastmath: NaN and ±inf keep their IEEE meaning, which
# the confidences rely on (NaN = unavailable, log 0 = -inf).
_FM = {"contract"}

_F = np.float32
_LOG2E = _F(1.4426950408889634)
_SHIFT = _F(12582912.0)  # 1.5 * 2^23: adding it rounds to an integer kept in the low bits
_LN2_HI = _F(0.693359375)  # ln 2 split so that n * _LN2_HI is exact (Cody-Waite)
_LN2_LO = _F(-2.12194440e-4)
_EXP_MIN = _F(-87.0)  # below: 0 (e^-87 is the smallest normal float32's order)
_EXP_MAX = _F(88.0)
_ONE = _F(1.0)
_TWO = _F(2.0)
_ZERO = _F(0.0)
_NAN32 = _F(np.nan)
_NEG_INF32 = _F(-np.inf)
_INF32 = _F(np.inf)
_I127 = np.int32(127)
_I23 = np.int32(23)
# Taylor coefficients 1/k! of e^r for |r| <= ln2/2 (relative error < 1e-7 after r^7)
_E2, _E3, _E4, _E5, _E6, _E7 = (_F(1 / 2), _F(1 / 6), _F(1 / 24), _F(1 / 120), _F(1 / 720),
                                _F(1 / 5040))  # fmt: skip
# 1/(2k+1) of atanh's series: log1p(u) = 2 atanh(s), s = u/(2+u) <= 1/3 (error < 1e-8)
_A3, _A5, _A7, _A9, _A11, _A13 = (_F(1 / 3), _F(1 / 5), _F(1 / 7), _F(1 / 9), _F(1 / 11),
                                  _F(1 / 13))  # fmt: skip


# numba calls an intrinsic with the typing context and the arguments' types, and its codegen
# with the target context, the IR builder, the signature and the arguments' values.
@_intrinsic
def _f32_from_bits(_typingctx: Any, _bits: Any) -> tuple[Any, _Codegen]:
    """The float32 whose bit pattern is the int32 ``bits`` (vectorises: a register move)."""
    sig = types.float32(types.int32)

    def codegen(_context: Any, builder: Any, _signature: Any, args: Any) -> Any:
        return builder.bitcast(args[0], ir.FloatType())

    return sig, codegen


@_intrinsic
def _bits_of_f32(_typingctx: Any, _x: Any) -> tuple[Any, _Codegen]:
    """The int32 bit pattern of the float32 ``x``."""
    sig = types.int32(types.float32)

    def codegen(_context: Any, builder: Any, _signature: Any, args: Any) -> Any:
        return builder.bitcast(args[0], ir.IntType(32))

    return sig, codegen


# The kernel's helpers, with its float semantics (LLVM inlines them).
_inline = _compiled(cache=True, nogil=True, fastmath=_FM, error_model="numpy")


@_inline
def _exp32(x: np.float32) -> np.float32:
    """e^x in float32 without a library call, so loops over frames vectorise: relative error
    < 1e-7; exactly 0 below -87 (and for -inf), +inf above 88, 1 at 0, NaN for NaN."""
    y = min(max(x, _EXP_MIN), _EXP_MAX)
    t = y * _LOG2E + _SHIFT
    n = t - _SHIFT  # round(y / ln 2)
    r = y - n * _LN2_HI - n * _LN2_LO
    p = _E7 * r + _E6
    p = p * r + _E5
    p = p * r + _E4
    p = p * r + _E3
    p = p * r + _E2
    p = p * r + _ONE
    p = p * r + _ONE
    e = p * _f32_from_bits((_bits_of_f32(t) + _I127) << _I23)  # p * 2^n
    e = _ZERO if x < _EXP_MIN else e
    e = _INF32 if x > _EXP_MAX else e
    return x if x != x else e


@_inline
def _logistic32(z: np.float32) -> np.float32:
    """1 / (1 + e^z): 1 at z = -inf, 0 at +inf, NaN for NaN (paper eq. 2's curve)."""
    return _ONE / (_ONE + _exp32(z))


@_inline
def _softplus32(z: np.float32) -> np.float32:
    """log(1 + e^z) = -log of the logistic 1/(1 + e^z), absolute error < 2e-7 for any z:
    0 at -inf, +inf at +inf, NaN for NaN."""
    u = _exp32(-abs(z))  # in [0, 1]
    s = u / (_TWO + u)  # log1p(u) = 2 atanh(s), s <= 1/3
    s2 = s * s
    p = _A13 * s2 + _A11
    p = p * s2 + _A9
    p = p * s2 + _A7
    p = p * s2 + _A5
    p = p * s2 + _A3
    p = p * s2 + _ONE
    return max(z, _ZERO) + _TWO * s * p


@_inline
def _argument(v: float, edge0: float, edge1: float, z: float, below: np.float32,
              above: np.float32) -> np.float32:  # fmt: skip
    """The argument of the logistic 1/(1 + e^z) for a value v against its band
    [edge0, edge1]: z inside (float64 in, so the band is decided and v - τ taken exactly as
    the reference does), ``below``/``above`` (±inf: a confidence of exactly 1 or 0) outside,
    NaN for NaN."""
    a = _F(z)
    a = below if v < edge0 else a
    return above if v > edge1 else a


@_inline
def _load_block(a: np.ndarray, cols: np.ndarray, g0: int, count: int, buf: np.ndarray) -> None:
    """buf[i, j] = a[g0 + j, cols[i]] for j < count, NaN outside the clip: a block of
    frames transposed so that each column's series is contiguous (the rows cols lists, all
    >= 0). ``a`` is row-major (a frame's values contiguous); unsigned indices, because a
    signed one is checked for wrap-around on every access."""
    frames = a.shape[0]
    lead = min(count, max(0, -g0))
    top = max(lead, min(count, frames - g0))
    n = cols.shape[0]
    for i in range(n):
        for j in range(lead):
            buf[i, j] = np.nan
        for j in range(top, count):
            buf[i, j] = np.nan
    for j in range(lead, top):
        g = np.uintp(g0 + j)
        for i in range(n):
            buf[i, j] = a[g, cols[i]]


@_inline
def _instant(x: np.ndarray, band: np.ndarray, three: bool, z: np.ndarray, clo: np.ndarray,
             cup: np.ndarray, nb: int) -> None:  # fmt: skip
    """Eqs. 2-3 over a block: clo = C(s0), cup = C(sn) of a three-state fluent (else 0);
    NaN for NaN. Two passes: the band decisions in float64 (4 lanes), then the logistic in
    float32 (8 lanes)."""
    e0, e1, tau, k = band[0], band[1], band[2], band[3]
    for j in range(nb):
        z[j] = _argument(x[j], e0, e1, (x[j] - tau) * k, _NEG_INF32, _INF32)
    for j in range(nb):
        clo[j] = _logistic32(z[j])
    if three:
        e0, e1, tau, k = band[4], band[5], band[6], band[7]
        for j in range(nb):
            z[j] = _argument(x[j], e0, e1, (x[j] - tau) * k, _NEG_INF32, _INF32)
        for j in range(nb):
            cup[j] = _ONE - _logistic32(z[j])
    else:
        for j in range(nb):
            cup[j] = clo[j] if clo[j] != clo[j] else _ZERO


@_inline
def _log_c(d: np.ndarray, mo: np.ndarray, one_logistic: bool, z0: np.ndarray,
           z1: np.ndarray, lc0: np.ndarray, lc1: np.ndarray, count: int) -> None:  # fmt: skip
    """lc0/lc1[j] = log C of the Δ d[j] toward s0 / sn (eq. 5's factors; mo: the fluent's
    motion row): 0 for a factor 1, -inf for a factor 0, NaN for NaN.

    ``one_logistic``: the two bands touch at most at Δ = 0 (τ >= δ, as by default), where
    both logistics have the same argument k(τ - |Δ|); every Δ then has at most one finite
    argument besides ±inf, so one softplus serves both directions."""
    e0, e1, tau0, k0, e4, e5, tau1, k1 = mo[0], mo[1], mo[2], mo[3], mo[4], mo[5], mo[6], mo[7]
    for j in range(count):
        v = d[j]
        z_lo = (tau1 - abs(v)) * k1 if one_logistic else (v - tau0) * k0
        z_hi = (tau1 - abs(v)) * k1 if one_logistic else (tau1 - v) * k1
        # toward s0: factor 1 below its band, 0 above; toward sn: 0 below, 1 above
        z0[j] = _argument(v, e0, e1, z_lo, _NEG_INF32, _INF32)
        z1[j] = _argument(v, e4, e5, z_hi, _INF32, _NEG_INF32)
    if one_logistic:
        for j in range(count):
            a, b = z0[j], z1[j]
            sp = _softplus32(a if a < b else b)  # the finite one (or NaN, or -inf)
            lc0[j] = _NEG_INF32 if a == _INF32 else -sp
            lc1[j] = _NEG_INF32 if b == _INF32 else -sp
    else:
        for j in range(count):
            lc0[j] = -_softplus32(z0[j])
            lc1[j] = -_softplus32(z1[j])


@_inline
def _window_sums(lc0: np.ndarray, lc1: np.ndarray, newest: int, step: int, window: int,
                 weight: np.ndarray, m0: np.ndarray, m1: np.ndarray, nb: int) -> None:  # fmt: skip
    """m[j] = Σ_a weight[a] · lc[newest + j - a·step]: eq. 5's log-sum over the window."""
    src0, src1 = lc0[newest:], lc1[newest:]
    for j in range(nb):
        m0[j] = src0[j]
        m1[j] = src1[j]
    for a in range(1, window):
        w = weight[a]
        src0, src1 = lc0[newest - a * step :], lc1[newest - a * step :]
        for j in range(nb):
            m0[j] += w * src0[j]
            m1[j] += w * src1[j]


@_inline
def _window_exp(m0: np.ndarray, m1: np.ndarray, one_logistic: bool, nb: int) -> None:
    """The products of eq. 5 from their log-sums: exp, with -inf -> 0 and NaN kept. With one
    logistic, the two sums are equal or one is -inf (a Δ on the wrong side of 0), so one exp
    serves both."""
    if one_logistic:
        for j in range(nb):
            a, b = m0[j], m1[j]
            e = _exp32(a if a > b else b)
            m0[j] = _ZERO if a == _NEG_INF32 else e
            m1[j] = _ZERO if b == _NEG_INF32 else e
    else:
        for j in range(nb):
            m0[j] = _exp32(m0[j])
            m1[j] = _exp32(m1[j])


@_inline
def _temporal_integer(xb: np.ndarray, f0: int, nb: int, step: int, window: int,
                      mo: np.ndarray, one_logistic: bool, weight: np.ndarray, d: np.ndarray,
                      z0: np.ndarray, z1: np.ndarray, lc0: np.ndarray, lc1: np.ndarray,
                      m0: np.ndarray, m1: np.ndarray) -> None:  # fmt: skip
    """Eq. 5 for an integer lag over frames f0 .. f0+nb-1: the Δ of age a at frame f is the
    newest Δ of frame f - a·step, so log C of each Δ is computed once (over the block and the
    (window-1)·step frames before it) and the window is a weighted sum of logs.

    xb: the signal from frame f0 - window·step on. Writes m0/m1 (toward s0 / sn): NaN where
    the frame has no Δ yet; a Δ the clip has no history for counts as a factor 1.
    """
    span = (window - 1) * step + nb
    g_first = f0 - (window - 1) * step  # frame of d[0]; xb[j + step] is that frame
    later = xb[step:]
    for j in range(span):
        d[j] = later[j] - xb[j]
    _log_c(d, mo, one_logistic, z0, z1, lc0, lc1, span)
    for j in range(min(span, max(0, step - g_first))):  # frames before the first Δ
        lc0[j] = _ZERO
        lc1[j] = _ZERO
    _window_sums(lc0, lc1, (window - 1) * step, step, window, weight, m0, m1, nb)
    _window_exp(m0, m1, one_logistic, nb)
    for j in range(min(nb, max(0, step - f0))):
        m0[j] = _NAN32
        m1[j] = _NAN32


@_inline
def _temporal_fractional(xb: np.ndarray, base: int, frames: int, f0: int, nb: int, lag: float,
                         window: int, mo: np.ndarray, one_logistic: bool, weight: np.ndarray,
                         samples: np.ndarray, ok: np.ndarray, d: np.ndarray, z0: np.ndarray,
                         z1: np.ndarray, lc0: np.ndarray, lc1: np.ndarray, m0: np.ndarray,
                         m1: np.ndarray) -> None:  # fmt: skip
    """Eq. 5 for a fractional lag: the window+1 samples of each frame interpolated like the
    reference (position f - m·lag clipped to the clip; the frame itself where the weight is
    0), and each Δ's log C computed for its own frame. xb[j] is frame base + j."""
    for m in range(window + 1):
        q = m * lag
        for j in range(nb):
            pos = (f0 + j) - q
            ok[m, j] = pos >= -1e-9
            pos = min(max(pos, 0.0), frames - 1.0)
            lo = int(math.floor(pos))
            hi = min(lo + 1, frames - 1)
            w = pos - lo
            a = xb[lo - base]
            samples[m, j] = a if w == 0.0 else a * (1.0 - w) + xb[hi - base] * w
    for j in range(nb):
        m0[j] = _ZERO
        m1[j] = _ZERO
    for a in range(window):
        w32 = weight[a]
        for j in range(nb):
            d[j] = samples[a, j] - samples[a + 1, j]
        _log_c(d, mo, one_logistic, z0, z1, lc0, lc1, nb)
        for j in range(nb):
            defined = ok[a + 1, j]  # no history: a factor 1
            m0[j] += w32 * (lc0[j] if defined else _ZERO)
            m1[j] += w32 * (lc1[j] if defined else _ZERO)
    _window_exp(m0, m1, one_logistic, nb)
    for j in range(nb):
        m0[j] = m0[j] if ok[1, j] else _NAN32
        m1[j] = m1[j] if ok[1, j] else _NAN32


@_inline
def _write(out: np.ndarray, col: int, c: np.ndarray, f0: int, nb: int) -> None:
    dst = out[col, f0:]
    for j in range(nb):
        dst[j] = c[j]


@_inline
def _write_complement(out: np.ndarray, col: int, c: np.ndarray, f0: int, nb: int) -> None:
    """out[col, f0 + j] = 1 - c[j]: the upper state of a two-state fluent (eq. 3)."""
    dst = out[col, f0:]
    for j in range(nb):
        dst[j] = _ONE - c[j]


@_inline
def _write_neither(out: np.ndarray, col: int, c0: np.ndarray, c1: np.ndarray, f0: int,
                   nb: int) -> None:  # fmt: skip
    """out[col, f0 + j] = (1 - c0[j]) (1 - c1[j]): a middle or no-motion state (eqs. 4, 6)."""
    dst = out[col, f0:]
    for j in range(nb):
        dst[j] = (_ONE - c0[j]) * (_ONE - c1[j])


@_inline
def _write_states(out: np.ndarray, cols: np.ndarray, paired: bool, clo: np.ndarray,
                  cup: np.ndarray, m0: np.ndarray, m1: np.ndarray, f0: int,
                  nb: int) -> None:  # fmt: skip
    """A fluent's columns for one block (a tilt pair's middle and no-motion come later)."""
    if cols[LO] >= 0:
        _write(out, cols[LO], clo, f0, nb)
    if cols[HI] >= 0:
        _write(out, cols[HI], cup, f0, nb)
    if cols[TWO_HI] >= 0:
        _write_complement(out, cols[TWO_HI], clo, f0, nb)
    if cols[MID] >= 0 and not paired:
        _write_neither(out, cols[MID], clo, cup, f0, nb)
    if cols[M_LO] >= 0:
        _write(out, cols[M_LO], m0, f0, nb)
    if cols[M_HI] >= 0:
        _write(out, cols[M_HI], m1, f0, nb)
    if cols[STILL] >= 0 and not paired:
        _write_neither(out, cols[STILL], m0, m1, f0, nb)


@_inline
def _write_touching(out: np.ndarray, col: int, dist_m: np.ndarray, touching_m: float, f0: int,
                    nb: int) -> None:  # fmt: skip
    """Touching at frames f0 .. f0+nb-1: 1 within touching_m metres, else 0; NaN for an
    unknown distance. dist_m: the distance over the block (its frame f0 at index 0)."""
    dst = out[col, f0:]
    for j in range(nb):
        dm = dist_m[j]
        dst[j] = _NAN32 if dm != dm else (_ONE if dm <= touching_m else _ZERO)


@_inline
def _write_pairs(out: np.ndarray, out_col: np.ndarray, partner: np.ndarray,
                 not_extreme: np.ndarray, not_moving: np.ndarray, f0: int,
                 nb: int) -> None:  # fmt: skip
    """A tilt pair shares "upright" and "tilt steady": both directions must hold. Each
    fluent's row of not_extreme / not_moving holds its own (1 - C)(1 - C) for the block."""
    for i in range(partner.shape[0]):
        p = partner[i]
        if p == i:
            continue
        for col, both in ((out_col[i, MID], not_extreme), (out_col[i, STILL], not_moving)):
            if col >= 0:
                a, b, dst = both[i], both[p], out[col, f0:]
                for j in range(nb):
                    dst[j] = a[j] * b[j]


@_compiled(cache=True, nogil=True)
def _age_weights(window: int) -> np.ndarray:
    """``(window,)`` float32: eq. 5's exponent 1/(a+1) of the Δ of age a."""
    weight = np.empty(window, np.float32)
    for a in range(window):
        weight[a] = 1.0 / (a + 1)
    return weight


@_compiled(cache=True, nogil=True)
def _one_logistic(motion: np.ndarray) -> np.ndarray:
    """``(n,)`` bool: the fluent's two motion bands touch at most at Δ = 0 with the same
    slope (τ >= δ, the default), so one logistic serves both directions (see _log_c)."""
    out = np.empty(motion.shape[0], np.bool_)
    for i in range(motion.shape[0]):
        mo = motion[i]
        out[i] = (mo[1] <= mo[4]) & (mo[2] == -mo[6]) & (mo[3] == mo[7])
    return out


@_compiled(cache=True, nogil=True)
def _pitch(count: int, itemsize: int) -> int:
    """A row length of at least ``count`` items whose byte size is an odd multiple of 64 (a
    cache line): consecutive rows start in different L1 sets and never 4 kB apart, where
    loads and stores would falsely alias."""
    lines = (count * itemsize + 63) // 64
    lines += 1 - lines % 2
    return lines * 64 // itemsize


@_compiled(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def fluent_columns(
    values: np.ndarray,
    distances_m: np.ndarray,
    sig_col: np.ndarray,
    dist_col: np.ndarray,
    inst: np.ndarray,
    motion: np.ndarray,
    three: np.ndarray,
    partner: np.ndarray,
    touching_m: float,
    lag: float,
    window: int,
    out_col: np.ndarray,
    out: np.ndarray,
) -> None:
    """Fill ``out`` ``(n_states, frames)`` float32, every state's confidence over time (the
    transpose of the result: each state's series is written contiguously).

    values: ``(frames, n_signals)`` signals; distances_m: ``(frames, n_pairs)`` near distances
    in metres (either layout). Per fluent i (n of them): ``sig_col[i]`` its column in
    ``values``; ``dist_col`` the columns of ``distances_m`` of the fluents that have a
    touching state, in fluent order;
    ``inst[i]`` = (lower τ-δ, τ+δ, τ, k, upper τ-δ, τ+δ, τ, k) and ``motion[i]`` = (toward-s0
    τ-δ, τ+δ, τ, k, toward-sn τ-δ, τ+δ, τ, k), k = ln((1-ε)/ε)/δ; ``three[i]``: has an upper
    boundary; ``partner[i]``: the other fluent of a tilt pair (or i); ``out_col[i, code]``:
    the row of ``out`` of each state code (LO..STILL), -1 where the fluent has none. Rows of
    ``out`` that no fluent names are left as they are. ``lag``: source frames per reference
    interval; ``window``: r.
    """
    frames = values.shape[0]
    n = sig_col.shape[0]
    integer_lag = lag >= 1.0 and lag == math.floor(lag)
    step = int(lag) if integer_lag else 0
    hist = window * step if integer_lag else int(math.ceil(window * lag)) + 1
    size = hist + BLOCK
    # Scratch rows, their starts staggered (see _pitch); a block's buffers stay in L1.
    xb = np.empty((n, _pitch(size + 1, 8)))  # each signal over the block and its history
    db = np.empty((dist_col.shape[0], _pitch(BLOCK, 8)))  # the touching fluents' distances
    d = np.empty(size)
    scratch = np.empty((8, _pitch(size, 4)), np.float32)
    z0, z1, lc0, lc1 = scratch[0], scratch[1], scratch[2], scratch[3]
    clo, cup, m0, m1 = scratch[4], scratch[5], scratch[6], scratch[7]
    samples = np.empty((window + 1, BLOCK))
    ok = np.empty((window + 1, BLOCK), np.bool_)
    weight = _age_weights(window)
    one_logistic = _one_logistic(motion)
    # a tilt pair's middle and no-motion states need both fluents: kept per block
    not_extreme = np.empty((n, _pitch(BLOCK, 4)), np.float32)
    not_moving = np.empty((n, _pitch(BLOCK, 4)), np.float32)
    for f0 in range(0, frames, BLOCK):
        nb = min(BLOCK, frames - f0)
        _load_block(values, sig_col, f0 - hist, hist + nb + 1, xb)
        _load_block(distances_m, dist_col, f0, nb, db)
        touching = 0
        for i in range(n):
            x = xb[i]
            _instant(x[hist:], inst[i], three[i], z0, clo, cup, nb)
            if integer_lag:
                _temporal_integer(x, f0, nb, step, window, motion[i], one_logistic[i],
                                  weight, d, z0, z1, lc0, lc1, m0, m1)  # fmt: skip
            else:
                _temporal_fractional(x, f0 - hist, frames, f0, nb, lag, window, motion[i],
                                     one_logistic[i], weight, samples, ok, d, z0, z1, lc0,
                                     lc1, m0, m1)  # fmt: skip
            paired = partner[i] != i
            _write_states(out, out_col[i], paired, clo, cup, m0, m1, f0, nb)
            if out_col[i, TOUCH] >= 0:
                _write_touching(out, out_col[i, TOUCH], db[touching], touching_m, f0, nb)
                touching += 1
            if paired:
                _write_neither(not_extreme, i, clo, cup, 0, nb)
                _write_neither(not_moving, i, m0, m1, 0, nb)
        _write_pairs(out, out_col, partner, not_extreme, not_moving, f0, nb)


@_compiled(cache=True, nogil=True)
def all_nan_columns(a: np.ndarray) -> np.ndarray:
    """``(cols,)`` bool: every value of the column of a ``(rows, cols)`` is NaN (a column
    stops at its first number, so a signal that exists costs next to nothing)."""
    out = np.ones(a.shape[1], np.bool_)
    for c in range(a.shape[1]):
        for r in range(a.shape[0]):
            if a[r, c] == a[r, c]:
                out[c] = False
                break
    return out


# ---------------------------------------------------------------------------------------------
# State signals (features.signals): the body frame, 22 angles and the near distances per frame.
# Each helper repeats the float operations of features.geometry in the same order (cross
# product terms, a·b summed left to right), so the two backends agree to the last bit or two.

Vec = tuple[float, float, float]


@_compiled(cache=True, nogil=True)
def _get(p: np.ndarray, f: int, j: int) -> Vec:
    return (p[f, j, 0], p[f, j, 1], p[f, j, 2])


@_compiled(cache=True, nogil=True)
def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@_compiled(cache=True, nogil=True)
def _mid(a: Vec, b: Vec) -> Vec:
    return (0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]))


@_compiled(cache=True, nogil=True)
def _dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@_compiled(cache=True, nogil=True)
def _cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@_compiled(cache=True, nogil=True)
def _unit(v: Vec, min_len: float) -> Vec:
    n = math.sqrt(_dot(v, v))
    if n >= min_len:
        return (v[0] / n, v[1] / n, v[2] / n)
    return (np.nan, np.nan, np.nan)


@_compiled(cache=True, nogil=True)
def _project(v: Vec, n: Vec) -> Vec:
    d = _dot(v, n)
    return (v[0] - d * n[0], v[1] - d * n[1], v[2] - d * n[2])


@_compiled(cache=True, nogil=True)
def _angle(u: Vec, v: Vec, min_len: float) -> float:
    nu = math.sqrt(_dot(u, u))
    nv = math.sqrt(_dot(v, v))
    if nu >= min_len and nv >= min_len:
        return math.acos(min(max(_dot(u, v) / (nu * nv), -1.0), 1.0))
    return np.nan


@_compiled(cache=True, nogil=True)
def state_signal_values(
    p: np.ndarray, joints: np.ndarray, near_a: np.ndarray, near_b: np.ndarray,
    min_len: float, hipless: bool, upright_head: float, values: np.ndarray,
    head_length: np.ndarray, dist_m: np.ndarray,
) -> None:  # fmt: skip
    """Fill the signals of :func:`features.signals.state_signals` from canonical positions.

    p: ``(frames, 33, 3)``; joints: canonical indices of (nose, left/right ear, shoulder,
    elbow, wrist, hip, knee, ankle) in that order; near_a/near_b: ``(n_pairs,)`` joint indices;
    hipless: the frame of the shoulders and the world's up (a clip without hips,
    :func:`features.geometry.shoulder_axes`), the armpit angle from its down, none where
    the head leans more than upright_head (radians) from the world's up.
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
        if hipless:
            left = _unit(_sub(ls, rs), min_len)
            up = _unit(_project(up_w, left), min_len)
            forward = _unit(_cross(left, up), min_len)
            if _angle(_sub(mid_ear, neck), up_w, min_len) > upright_head:  # lying, bent over
                left = up = forward = (np.nan, np.nan, np.nan)
        else:
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
            down = (-up[0], -up[1], -up[2]) if hipless else _sub(hip, sh)
            values[f, 4 + side] = _angle(arm, down, min_len)
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
        link = math.sqrt(_dot(e, e))
        hl = 2.0 * link if link >= min_len else np.nan  # a degenerate link: no unit
        head_length[f] = hl
        for k in range(n_pairs):
            d = _sub(_get(p, f, near_a[k]), _get(p, f, near_b[k]))
            dm = math.sqrt(_dot(d, d))
            dist_m[f, k] = dm
            values[f, 22 + k] = dm / hl
