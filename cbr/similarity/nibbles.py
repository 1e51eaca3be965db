"""A first-stage lower bound on Euclidean distances from 4-bit codes, read 64 cases at a time.

Every value ``x_j`` of a case lies in one of 16 cells of its dimension (edges ``E_j[0..16]``,
equal widths over the dimension's range): its 4-bit code ``c`` with ``E_j[c] <= x_j <=
E_j[c + 1]``, and ``x_hat`` is the case's point of cell centres ``C_j[c]``, with the exact
norm ``e_x = |x - x_hat|`` kept per case (rounded up). The triangle inequality gives
``|q - x| >= |q - x_hat| - e_x``. Per query, the 16 values ``(q_j - C_j[c])^2`` of every
dimension are scaled by ``s`` (the largest to 255) and rounded down to a byte table
(asymmetric distance computation, as in product quantisation's fast scan): a case's sum ``S``
of table entries is at most ``s |q - x_hat|^2``, and exact in uint16 (at most 257 dimensions
of at most 255). A case cannot be within ``sqrt(L)`` of the query when ``S / s > (sqrt(L) +
e_x)^2``: the scan first drops every case with ``S > floor(s (sqrt(L) + max e_x)^2)`` (the
sum, an integer, is then above that value), then checks the survivors with their own ``e_x``.
On uniform data this bound lets through about a quarter of what the cell-gap bound
``sum_j dist(q_j, cell)^2`` does with the same bytes (measured on 2e5 x 200 uniform rows).

The codes are stored in blocks of 64 cases, dimension-major: byte ``t`` of dimension ``j``
of a block holds case ``t``'s code in its low nibble and case ``32 + t``'s in its high nibble,
so one byte shuffle (``pshufb``, AVX2) looks up 32 cases' table entries at once, and a block's
64 sums come from ``2 m`` shuffles over ``32 m`` bytes: half the bytes of 8-bit codes, with
no multiplication. A scalar kernel computes the same sums on any CPU (the reference the
shuffle is tested against); where the CPU lacks AVX2 (or numba is told to compile for another
CPU) the Euclidean index keeps its 8-bit codes instead, which are faster than that kernel.
"""

from __future__ import annotations

import math
import platform
from dataclasses import dataclass
from functools import cached_property

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

NIBBLE_BLOCK = 64  # cases per block: 32 bytes a dimension, two cases a byte
MAX_DIMS = 257  # 257 * 255 < 2^16: a case's table sum is exact in uint16


def _host_has_avx2() -> bool:
    """Whether numba compiles for this machine's CPU and it has AVX2's byte shuffle."""
    x86 = platform.machine().lower() in ("x86_64", "amd64")
    if getattr(numba.config, "CPU_NAME", None) or not x86:
        return False
    import llvmlite.binding as llvm

    return bool(llvm.get_host_cpu_features().get("avx2", False))


HAS_SHUFFLE = _host_has_avx2()

_I8, _I16, _I32, _I64 = ir.IntType(8), ir.IntType(16), ir.IntType(32), ir.IntType(64)
_BYTES = ir.VectorType(_I8, 32)
_WORDS = ir.VectorType(_I16, 32)


def _shuffle(builder: ir.IRBuilder, table: ir.Value, idx: ir.Value) -> ir.Value:
    """``table[idx]`` per byte within each 16-byte half (idx < 16): AVX2's ``pshufb``, or the
    same lane by lane where the compiler's target lacks it (never run there: see
    :data:`HAS_SHUFFLE`, but it must compile)."""
    if HAS_SHUFFLE:
        kind = ir.FunctionType(_BYTES, [_BYTES, _BYTES])
        name = "llvm.x86.avx2.pshuf.b"
        fn = cgutils.get_or_insert_function(builder.module, kind, name)  # type: ignore[no-untyped-call]
        return builder.call(fn, [table, idx])
    out = ir.Constant(_BYTES, None)
    for lane in range(32):
        i = builder.zext(builder.extract_element(idx, ir.Constant(_I32, lane)), _I32)
        i = builder.add(i, ir.Constant(_I32, lane // 16 * 16))
        out = builder.insert_element(
            out, builder.extract_element(table, i), ir.Constant(_I32, lane)
        )
    return out


@intrinsic
def shuffle_block_mask(_typingctx, codes, start, luts, m, limit, sums):  # type: ignore[no-untyped-def]
    """The mask (int64, bit ``t`` for case ``t``) of the block's cases whose table sum is at
    most ``limit``, the sums written to ``sums`` ``(64,)`` uint16: ``codes`` uint8 1-d, the
    block's ``32 m`` bytes from ``start``; ``luts`` uint8 1-d ``(m 32,)``, each dimension's
    16 entries twice (one per 16-byte half)."""
    sig = types.int64(codes, start, luts, m, limit, sums)

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        codes_a = context.make_array(signature.args[0])(context, builder, args[0])
        luts_a = context.make_array(signature.args[2])(context, builder, args[2])
        first = builder.gep(codes_a.data, [args[1]])
        zero = ir.Constant(_WORDS, None)
        acc_lo = cgutils.alloca_once_value(builder, zero)  # type: ignore[no-untyped-call]
        acc_hi = cgutils.alloca_once_value(builder, zero)  # type: ignore[no-untyped-call]
        low4 = ir.Constant(_BYTES, [15] * 32)
        four = ir.Constant(_BYTES, [4] * 32)
        vec = _BYTES.as_pointer()
        with cgutils.for_range(builder, args[3]) as loop:
            off = builder.mul(loop.index, ir.Constant(loop.index.type, 32))
            byte = builder.load(builder.bitcast(builder.gep(first, [off]), vec), align=1)
            table = builder.load(builder.bitcast(builder.gep(luts_a.data, [off]), vec), align=1)
            lo = _shuffle(builder, table, builder.and_(byte, low4))
            hi = _shuffle(builder, table, builder.and_(builder.lshr(byte, four), low4))
            builder.store(builder.add(builder.load(acc_lo), builder.zext(lo, _WORDS)), acc_lo)
            builder.store(builder.add(builder.load(acc_hi), builder.zext(hi, _WORDS)), acc_hi)
        out = builder.bitcast(
            context.make_array(signature.args[5])(context, builder, args[5]).data,
            _WORDS.as_pointer(),
        )
        builder.store(builder.load(acc_lo), out, align=1)
        builder.store(builder.load(acc_hi), builder.gep(out, [ir.Constant(_I32, 1)]), align=1)
        lim = builder.trunc(args[4], _I16)
        splat = builder.insert_element(ir.Constant(_WORDS, None), lim, ir.Constant(_I32, 0))
        zeros = ir.Constant(ir.VectorType(_I32, 32), [0] * 32)
        splat = builder.shuffle_vector(splat, ir.Constant(_WORDS, None), zeros)
        low = builder.icmp_unsigned("<=", builder.load(acc_lo), splat)
        high = builder.icmp_unsigned("<=", builder.load(acc_hi), splat)
        low64 = builder.zext(builder.bitcast(low, _I32), _I64)
        high64 = builder.zext(builder.bitcast(high, _I32), _I64)
        return builder.or_(low64, builder.shl(high64, ir.Constant(_I64, 32)))

    return sig, codegen


@numba.njit(cache=True, nogil=True)
def shuffle_mask(
    codes: np.ndarray, start: int, luts: np.ndarray, m: int, limit: int, sums: np.ndarray
) -> int:
    """:func:`shuffle_block_mask` callable from Python (for tests; only where
    :data:`HAS_SHUFFLE`)."""
    mask: int = shuffle_block_mask(codes, start, luts, m, limit, sums)  # type: ignore[call-arg]
    return mask


@numba.njit(cache=True, nogil=True)
def scalar_block_mask(
    codes: np.ndarray, start: int, luts: np.ndarray, m: int, limit: int, sums: np.ndarray
) -> int:
    """:func:`shuffle_block_mask` by scalar loops (the same sums, for any CPU)."""
    sums[:] = 0
    for j in range(m):
        for t in range(32):
            byte = codes[start + 32 * j + t]
            sums[t] += np.uint16(luts[32 * j + (byte & 15)])
            sums[32 + t] += np.uint16(luts[32 * j + (byte >> 4)])
    mask = 0
    for t in range(NIBBLE_BLOCK):
        if sums[t] <= limit:
            mask |= 1 << t
    return mask


@numba.njit(cache=True, nogil=True)
def nibble_tables(q: np.ndarray, centres: np.ndarray) -> tuple[np.ndarray, float]:
    """The query's byte tables ``(m 32,)`` uint8 and their scale ``s``: entry ``c`` of
    dimension ``j`` is at most ``s (q_j - C_j[c])^2`` (rounded down), so a case's sum of
    entries over ``s`` never exceeds ``|q - x_hat|^2``. ``q`` ``(m,)`` float32, ``centres``
    ``(m, 16)`` float64. The float64 difference (a float32 value is exact in float64) and
    its square err by ``2^-52`` relative at most; they are shrunk by ``1e-12`` relative, and
    the scaled value again, so each rounded entry stays below the exact one."""
    m = centres.shape[0]
    sq = np.empty((m, 16))
    top = 0.0
    for j in range(m):
        v = np.float64(q[j])
        for c in range(16):
            g = v - centres[j, c]
            sq[j, c] = g * g * (1.0 - 1e-12)
            top = max(top, sq[j, c])
    # every entry 0 (a bound of 0: nothing pruned) when a square overflows
    scale = 255.0 / top if 0.0 < top < np.inf else 0.0
    luts = np.empty(m * 32, dtype=np.uint8)
    for j in range(m):
        for c in range(16):
            e = np.uint8(min(math.floor(sq[j, c] * scale * (1.0 - 1e-12)), 255.0))
            luts[32 * j + c] = e
            luts[32 * j + 16 + c] = e
    return luts, scale


@numba.njit(cache=True, nogil=True, inline="always")
def limit_code(limit: float, scale: float) -> int:
    """The largest table sum ``floor(s limit)`` that may not be pruned (65535, every sum,
    when that is out of uint16's range)."""
    v = limit * scale
    return 65535 if not v < 65535.0 else int(math.floor(v))


@dataclass(frozen=True, eq=False)
class NibbleCodes:
    """Every case's values as 4-bit codes (module docstring) in blocks of 64 cases."""

    codes: np.ndarray  # (blocks * m * 32,) uint8, block-major, then dimension-major
    edges: np.ndarray  # (m, 17) float64 each dimension's cell edges
    centres: np.ndarray  # (m, 16) float64 each cell's centre
    errs: np.ndarray  # (n,) float32 e_x = |x - x_hat| rounded up
    n: int  # cases (the last block is padded with code 0, never reported)

    @property
    def nbytes(self) -> int:
        """Memory the codes, edges, centres and errors take."""
        return int(self.codes.nbytes + self.edges.nbytes + self.centres.nbytes + self.errs.nbytes)

    @cached_property
    def top_err(self) -> float:
        """The largest ``e_x``."""
        return float(self.errs.max()) if self.n else 0.0


def nibble_codes(rows: np.ndarray) -> NibbleCodes | None:
    """The 4-bit codes of ``rows`` ``(n, m)`` float32 (every value finite, ``m <=
    MAX_DIMS``), read in chunks (a memmap is never copied whole); None when no dimension has
    a range or a range overflows."""
    n, m = rows.shape
    lo, hi = np.full(m, np.inf), np.full(m, -np.inf)
    chunk = 1 << 16
    for a in range(0, n, chunk):
        part = np.asarray(rows[a : a + chunk])
        lo = np.minimum(lo, part.min(axis=0).astype(np.float64))
        hi = np.maximum(hi, part.max(axis=0).astype(np.float64))
    if not (np.any(hi > lo) and np.all(np.isfinite(hi - lo))):
        return None
    edges = lo[:, None] + (hi - lo)[:, None] * (np.arange(17) / 16.0)
    edges[:, 0], edges[:, 16] = lo, hi  # exact ends: every value lies inside
    centres = 0.5 * (edges[:, :16] + edges[:, 1:])
    blocks = -(-n // NIBBLE_BLOCK)
    codes = np.zeros(blocks * m * 32, dtype=np.uint8)
    errs = np.empty(n, dtype=np.float32)
    for a in range(0, n, chunk):
        _encode(np.asarray(rows[a : a + chunk]), a, edges, centres, codes, errs)
    return NibbleCodes(codes, edges, centres, errs, n)


@numba.njit(cache=True, nogil=True)
def _encode(
    part: np.ndarray,
    first: int,
    edges: np.ndarray,
    centres: np.ndarray,
    codes: np.ndarray,
    errs: np.ndarray,
) -> None:
    """Codes and ``e_x`` of the rows ``part`` ``(c, m)`` float32 (rows ``first`` on, ``first``
    a multiple of 64) into ``codes`` and ``errs``. A value's cell is estimated from the range,
    then moved by exact comparisons with the edges so ``E[c] <= x <= E[c + 1]``. ``e_x`` is
    the float64 norm of ``x - x_hat``, raised (as :func:`~cbr.similarity.grid_codes._quantize`
    raises its error norms) above its rounding and then rounded up to float32."""
    m = part.shape[1]
    u = 2.0**-53
    for r in range(part.shape[0]):
        i = first + r
        base = (i // NIBBLE_BLOCK) * m * 32 + (i % 32)
        shift = 4 * ((i % NIBBLE_BLOCK) // 32)
        err = 0.0
        spread_x = 0.0
        spread_c = 0.0
        for j in range(m):
            x = np.float64(part[r, j])
            width = edges[j, 16] - edges[j, 0]
            c = (
                int(min(max(math.floor((x - edges[j, 0]) * (16.0 / width)), 0.0), 15.0))
                if width > 0.0
                else 0
            )
            while c > 0 and x < edges[j, c]:
                c -= 1
            while c < 15 and x >= edges[j, c + 1]:
                c += 1
            codes[base + 32 * j] |= np.uint8(c << shift)
            d = x - centres[j, c]
            err += d * d
            spread_x += x * x
            spread_c += centres[j, c] * centres[j, c]
        e = math.sqrt(err) * (1.0 + 4.0 * (m + 4) * u) + 4.0 * u * (
            math.sqrt(spread_x) + math.sqrt(spread_c)
        )
        e32 = np.float32(e)
        errs[i] = e32 if np.float64(e32) >= e else np.nextafter(e32, np.float32(np.inf))
