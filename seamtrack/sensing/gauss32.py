"""Float32 standard normals of a PCG64 Generator, drawn in numba: the very numbers (and the
generator's state after) of ``rng.standard_normal(n, dtype=np.float32)``, about 4x faster.

NumPy's float32 normals are the 256-layer ziggurat of Marsaglia and Tsang (2000, J. Stat.
Softw. 5(8)) on 32-bit words: 8 bits pick the layer, 1 bit the sign, 23 bits the abscissa;
each word is one half of a 64-bit PCG64 output, the low half first, the high half kept in the
bit generator (``has_uint32``, ``uinteger``) for the next word. Its C loop calls the bit
generator through a pointer for each word and spends about 9 ns a number. Here PCG64 itself
(O'Neill 2014: a 128-bit linear congruential step, output XSL-RR: the high and low halves
xor-ed, rotated by the top 6 bits) and the ziggurat run together in numba, from the state the
Generator holds, which is then set to where NumPy would have left it (the half-word kept).

The layer tables are rebuilt from the ziggurat's two constants (the rightmost layer edge r and
the layer area v) by Marsaglia and Tsang's recursion. On first use the result is compared with
NumPy's own draws; a difference (another NumPy), or a bit generator other than PCG64, falls
back to NumPy's call, so the numbers are NumPy's in every case.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic
from numpy.typing import NDArray

from seamtrack.jit import KERNEL

#: Rightmost edge and area of a layer of the 256-layer normal ziggurat.
ZIGGURAT_R = 3.6541528853610088
ZIGGURAT_V = 0.00492867323399
LAYERS = 256


def _tables() -> tuple[NDArray[np.uint32], NDArray[np.float32], NDArray[np.float32]]:
    """k_i (23-bit thresholds), w_i (abscissa scale), f_i = exp(-x_i^2 / 2) of the layers."""
    m = 2.0**23
    k = np.zeros(LAYERS)
    w = np.zeros(LAYERS)
    f = np.zeros(LAYERS)
    x = previous = ZIGGURAT_R
    q = ZIGGURAT_V / math.exp(-0.5 * x * x)
    k[0] = x / q * m
    w[0], w[-1] = q / m, x / m
    f[0], f[-1] = 1.0, math.exp(-0.5 * x * x)
    for i in range(LAYERS - 2, 0, -1):
        x = math.sqrt(-2.0 * math.log(ZIGGURAT_V / x + math.exp(-0.5 * x * x)))
        k[i + 1] = x / previous * m
        previous = x
        f[i] = math.exp(-0.5 * x * x)
        w[i] = x / m
    return np.round(k).astype(np.uint32), w.astype(np.float32), f.astype(np.float32)


_K, _W, _F = _tables()
_R_F = np.float32(ZIGGURAT_R)
_INV_R_F = np.float32(1.0 / ZIGGURAT_R)


#: PCG64's 128-bit multiplier (O'Neill's default), high and low halves.
_MULT_HI = np.uint64(0x2360ED051FC65DA4)
_MULT_LO = np.uint64(0x4385DF649FCCF645)
_MASK64 = (1 << 64) - 1


def _lcg_step_typing(typingctx: Any, hi: Any, lo: Any, inc_hi: Any, inc_lo: Any) -> tuple[Any, Any]:
    """PCG64's state step, (hi, lo) * MULT + (inc_hi, inc_lo) mod 2**128, in LLVM's 128-bit
    integers (on x86-64 one 64 x 64 -> 128 multiply and two 64-bit ones, where four 32-bit
    products and their carries took longer). Returns (hi, lo) after."""
    u64 = types.uint64
    sig = types.UniTuple(u64, 2)(u64, u64, u64, u64)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        i128, i64 = ir.IntType(128), ir.IntType(64)
        shift = ir.Constant(i128, 64)

        def join(high: Any, low: Any) -> Any:
            wide = builder.shl(builder.zext(high, i128), shift)
            return builder.or_(wide, builder.zext(low, i128))

        mult = ir.Constant(i128, (int(_MULT_HI) << 64) | int(_MULT_LO))
        after = builder.add(builder.mul(join(args[0], args[1]), mult), join(args[2], args[3]))
        high = builder.trunc(builder.lshr(after, shift), i64)
        return context.make_tuple(builder, signature.return_type, (high, builder.trunc(after, i64)))

    return sig, codegen


#: numba's intrinsic (typed ``Any``: mypy would see the typing function's signature).
_lcg_step: Any = intrinsic(_lcg_step_typing)


@numba.njit(**KERNEL)
def _word(
    hi: np.uint64, lo: np.uint64, inc_hi: np.uint64, inc_lo: np.uint64, has: bool, kept: np.uint64
) -> tuple[np.uint32, np.uint64, np.uint64, bool, np.uint64]:
    """NumPy's next_uint32 of PCG64: the kept high half if there is one, else the low half of
    a new output (its high half kept). The 128-bit state (hi, lo) steps as state * MULT + inc
    (:data:`_lcg_step`); the output is XSL-RR: (hi ^ lo) rotated right by the top 6 bits of
    hi. Returns (word, hi, lo, has, kept) after."""
    if has:
        return np.uint32(kept), hi, lo, False, kept
    high, low = _lcg_step(hi, lo, inc_hi, inc_lo)
    x = high ^ low
    rot = high >> np.uint64(58)
    out = (x >> rot) | (x << ((np.uint64(64) - rot) & np.uint64(63)))
    return np.uint32(out & np.uint64(0xFFFFFFFF)), high, low, True, out >> np.uint64(32)


@numba.njit(**KERNEL)
def _rejected(
    r: np.uint32, hi: np.uint64, lo: np.uint64, inc_hi: np.uint64, inc_lo: np.uint64,
    has: bool, kept: np.uint64, k: NDArray[np.uint32], w: NDArray[np.float32],
    f: NDArray[np.float32], r_f: np.float32, inv_r_f: np.float32,
) -> tuple[np.float32, np.uint64, np.uint64, bool, np.uint64]:  # fmt: skip
    """The ziggurat's rare branches (about 1 % of the numbers), from a word ``r`` outside its
    layer's rectangle: the tail beyond r (layer 0), or a wedge's test with a second word, and
    new words until a number is accepted. Returns (number, hi, lo, has, kept) after."""
    scale = np.float32(1.0 / 16777216.0)  # next_float: the word's top 24 bits
    sh8 = np.uint32(8)
    while True:
        idx = r & np.uint32(0xFF)
        rabs = (r >> np.uint32(9)) & np.uint32(0x7FFFFF)
        x = np.float32(rabs) * w[idx]
        if (r >> sh8) & np.uint32(1):
            x = -x
        if rabs < k[idx]:
            return x, hi, lo, has, kept
        if idx == 0:  # the tail beyond r
            while True:
                r1, hi, lo, has, kept = _word(hi, lo, inc_hi, inc_lo, has, kept)
                r2, hi, lo, has, kept = _word(hi, lo, inc_hi, inc_lo, has, kept)
                xx = -inv_r_f * np.log1p(-(np.float32(r1 >> sh8) * scale))
                yy = -np.log1p(-(np.float32(r2 >> sh8) * scale))
                if yy + yy > xx * xx:
                    break
            x = -(r_f + xx) if (rabs >> sh8) & np.uint32(1) else r_f + xx
            return x, hi, lo, has, kept
        r1, hi, lo, has, kept = _word(hi, lo, inc_hi, inc_lo, has, kept)
        u = np.float32(r1 >> sh8) * scale
        xd = np.float64(x)
        if np.float64((f[idx - 1] - f[idx]) * u + f[idx]) < math.exp(-0.5 * xd * xd):
            return x, hi, lo, has, kept
        r, hi, lo, has, kept = _word(hi, lo, inc_hi, inc_lo, has, kept)


@numba.njit(**KERNEL)
def _ziggurat(
    st: NDArray[np.uint64], out: NDArray[np.float32],
    k: NDArray[np.uint32], w: NDArray[np.float32], f: NDArray[np.float32],
    r_f: np.float32, inv_r_f: np.float32,
) -> None:  # fmt: skip
    """Fill ``out`` with NumPy's float32 ziggurat normals from the PCG64 state ``st`` =
    [state high, state low, increment high, increment low, has_uint32, uinteger], updated.
    A word inside its layer's rectangle (99 %) is the number at once; the rest go to
    :func:`_rejected`, out of the hot loop."""
    hi, lo, inc_hi, inc_lo = st[0], st[1], st[2], st[3]
    has, kept = st[4] != 0, st[5]
    for i in range(out.shape[0]):
        r, hi, lo, has, kept = _word(hi, lo, inc_hi, inc_lo, has, kept)
        idx = r & np.uint32(0xFF)
        rabs = (r >> np.uint32(9)) & np.uint32(0x7FFFFF)
        if rabs < k[idx]:
            x = np.float32(rabs) * w[idx]
            out[i] = -x if (r >> np.uint32(8)) & np.uint32(1) else x
        else:
            out[i], hi, lo, has, kept = _rejected(r, hi, lo, inc_hi, inc_lo, has, kept, k, w, f,
                                                  r_f, inv_r_f)  # fmt: skip
    st[0], st[1] = hi, lo
    st[4], st[5] = np.uint64(1) if has else np.uint64(0), kept


_checked: list[bool] = []


def _agrees() -> bool:
    """Whether this module's numbers are NumPy's (checked once, on a fixed seed, with and
    without a kept half-word at the start, and the generator's state after)."""
    if not _checked:
        ok = True
        for skip in (0, 1):
            a = np.random.Generator(np.random.PCG64(20240613))
            b = np.random.Generator(np.random.PCG64(20240613))
            if skip:
                a.standard_normal(1, dtype=np.float32)
                b.standard_normal(1, dtype=np.float32)
            mine = _draw(a, 200_003)
            ok &= np.array_equal(mine, b.standard_normal(200_003, dtype=np.float32))
            ok &= a.bit_generator.state == b.bit_generator.state
        _checked.append(bool(ok))
    return _checked[0]


def _draw(rng: np.random.Generator, n: int) -> NDArray[np.float32]:
    """n numbers from the Generator's PCG64 state, which is then set to where NumPy's own
    draw would have left it."""
    bg = rng.bit_generator
    state = dict(bg.state)
    pcg = dict(state["state"])
    st = np.array(
        [
            pcg["state"] >> 64,
            pcg["state"] & _MASK64,
            pcg["inc"] >> 64,
            pcg["inc"] & _MASK64,
            state["has_uint32"],
            state["uinteger"],
        ],
        dtype=np.uint64,
    )
    out = np.empty(n, dtype=np.float32)
    _ziggurat(st, out, _K, _W, _F, _R_F, _INV_R_F)
    pcg["state"] = (int(st[0]) << 64) | int(st[1])
    state["state"] = pcg
    state["has_uint32"], state["uinteger"] = int(st[4]), int(st[5])
    bg.state = state
    return out


def standard_normal_f32(
    rng: np.random.Generator, shape: int | tuple[int, ...]
) -> NDArray[np.float32]:
    """``rng.standard_normal(shape, dtype=np.float32)``: the same numbers and state after."""
    n = math.prod(shape) if isinstance(shape, tuple) else int(shape)
    if n == 0 or type(rng.bit_generator) is not np.random.PCG64 or not _agrees():
        return rng.standard_normal(shape, dtype=np.float32)
    return _draw(rng, n).reshape(shape)
