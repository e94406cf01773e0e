"""Compilation settings, shared constants and small scalar math for the CPU kernels.

Every kernel is compiled with `cache=True` (so the JIT cost is paid once per machine),
`error_model="numpy"` (no ZeroDivisionError branches, which would block vectorisation) and
`fastmath={"contract"}` (FMA contraction only: NaN/inf semantics stay IEEE, which the
culling tests rely on).

Kernels are generic in the float type of their arrays: float32 for speed, float64 for
gradient checks. Literal constants are written `F(...)` with `F = array.dtype.type` so that
float32 code is never silently promoted to float64. `splat_exp` and `splat_log` are the
only transcendental functions in hot loops: in float32 they are branch-free polynomials that
LLVM vectorises (about 2 ulp); in float64 they are exactly `math.exp` / `math.log`.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic, overload

# Twins of the constants of `morphosim_gym.render.reference` (which imports torch; the numpy hot
# path must not). tests/render checks that both sides agree.
TILE = 16
ALPHA_MIN = 1.0 / 255.0
ALPHA_MAX = 0.99
T_MIN = 1e-4
BLUR = 0.3
FOV_CLAMP = 1.3
EXTENT_MARGIN = 0.05

__all__ = [
    "jit", "pjit", "splat_exp", "splat_log", "float_bits", "atomic_add", "atomic_cas", "f32_rows", "f32_vector",
    "TILE", "ALPHA_MIN", "ALPHA_MAX", "T_MIN", "BLUR", "FOV_CLAMP", "EXTENT_MARGIN", "NREC",
    "R_MX", "R_MY", "R_CA", "R_CB", "R_CC", "R_OP", "R_Z", "R_R", "R_G", "R_B", "R_EX", "R_EY",
    "R_X0", "R_X1", "R_Y0", "R_Y1",
]

_OPTS = dict(cache=True, error_model="numpy", fastmath={"contract"}, nogil=True)

#: plain compiled function (hot-loop bodies, serial helpers)
jit = numba.njit(**_OPTS)


def pjit(fn):
    """Compile a thin `prange` wrapper (parallel=True). Keep the loop body in a plain `jit` function:
    numba's parallel lowering stops LLVM from vectorising code written inside the prange loop."""
    return numba.njit(parallel=True, **_OPTS)(fn)


# ----------------------------------------------------------------------------- record layout
# Projected Gaussians are stored one record (row of 16 floats, 64 bytes in float32) per
# Gaussian, so the rasteriser touches one cache line per Gaussian it visits.
# (module-level ints: numba freezes them as compile-time constants)
R_MX, R_MY = 0, 1              # pixel-space centre (x right, y down)
R_CA, R_CB, R_CC = 2, 3, 4     # conic: inverse of the blurred 2D covariance, [[CA, CB], [CB, CC]]
R_OP = 5                       # opacity
R_Z = 6                        # camera-space depth (sort key, depth output)
R_R, R_G, R_B = 7, 8, 9        # colour
R_EX, R_EY = 10, 11            # half-extents in pixels (incl. EXTENT_MARGIN)
R_X0, R_X1, R_Y0, R_Y1 = 12, 13, 14, 15   # inclusive pixel box clipped to the image (floats)
NREC = 16


# ----------------------------------------------------------------------------- bit casts
@intrinsic
def _i32_as_f32(typingctx, i):
    sig = types.float32(types.int32)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.FloatType())

    return sig, codegen


@intrinsic
def _f32_as_i32(typingctx, x):
    sig = types.int32(types.float32)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(32))

    return sig, codegen


@intrinsic
def float_bits(typingctx, x):
    """Raw IEEE bits of a float32 (-> uint32) or float64 (-> uint64). For positive floats the
    integer order equals the float order, which is what the depth radix sort relies on."""
    if x == types.float32:
        sig, width = types.uint32(types.float32), 32
    elif x == types.float64:
        sig, width = types.uint64(types.float64), 64
    else:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(width))

    return sig, codegen


@intrinsic
def atomic_add(typingctx, arr, idx, val):
    """arr[idx] += val atomically on an int64 array; returns the old value (work claiming)."""
    if not (isinstance(arr, types.Array) and arr.dtype == types.int64 and arr.ndim == 1):
        return None
    sig = types.int64(arr, types.intp, types.int64)

    def codegen(context, builder, signature, args):
        arrty = signature.args[0]
        ary = context.make_array(arrty)(context, builder, args[0])
        ptr = cgutils.get_item_pointer(context, builder, arrty, ary, [args[1]])
        return builder.atomic_rmw("add", ptr, args[2], "seq_cst")

    return sig, codegen


@intrinsic
def atomic_cas(typingctx, arr, idx, expected, new):
    """arr[idx] = new if arr[idx] == expected, atomically, on an int64 array; returns the old value
    (claim a view only while it is there to claim)."""
    if not (isinstance(arr, types.Array) and arr.dtype == types.int64 and arr.ndim == 1):
        return None
    sig = types.int64(arr, types.intp, types.int64, types.int64)

    def codegen(context, builder, signature, args):
        arrty = signature.args[0]
        ary = context.make_array(arrty)(context, builder, args[0])
        ptr = cgutils.get_item_pointer(context, builder, arrty, ary, [args[1]])
        pair = builder.cmpxchg(ptr, args[2], args[3], "seq_cst", "seq_cst")
        return builder.extract_value(pair, 0)

    return sig, codegen


# ----------------------------------------------------------------------------- arrays in place
@intrinsic
def _f32_pointer(typingctx, address):
    """A float32 pointer to a raw address (int64)."""
    if address != types.int64:
        return None
    sig = types.CPointer(types.float32)(types.int64)

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], context.get_value_type(signature.return_type))

    return sig, codegen


@numba.njit(**_OPTS)
def f32_rows(address, n, k):
    """The float32 array [n, k] (C order) at a raw address: an array the caller keeps alive and
    unchanged while kernels read it in place (`claimed.ClaimedBatch` references frozen inputs)."""
    return numba.carray(_f32_pointer(address), (n, k))


@numba.njit(**_OPTS)
def f32_vector(address, n):
    """The float32 array [n] at a raw address (as `f32_rows`)."""
    return numba.carray(_f32_pointer(address), n)


# ----------------------------------------------------------------------------- exp / log
def _exp32(x):
    # exp(x) = 2^n * exp(r), n = round(x / ln 2), |r| <= ln2 / 2; degree-6 Taylor for exp(r).
    # Inputs below -87 are clamped (the result is then < 1e-38, far below any threshold).
    F = np.float32
    x = max(x, F(-87.0))
    n = np.floor(x * F(1.4426950408889634) + F(0.5))
    r = x - n * F(0.693145751953125) - n * F(1.428606765330187e-06)
    p = F(1.0 / 720.0)
    p = p * r + F(1.0 / 120.0)
    p = p * r + F(1.0 / 24.0)
    p = p * r + F(1.0 / 6.0)
    p = p * r + F(0.5)
    p = p * r + F(1.0)
    p = p * r + F(1.0)
    return p * _i32_as_f32((np.int32(n) + np.int32(127)) << np.int32(23))


def _log32(x):
    # log(x) for finite x > 0 (normal): x = m 2^e with m in [sqrt(1/2), sqrt(2)),
    # log m = 2 atanh(s), s = (m - 1) / (m + 1), odd series to s^9 (|error| < 1e-9).
    F = np.float32
    bits = _f32_as_i32(x)
    e = (bits >> np.int32(23)) - np.int32(127)
    m = _i32_as_f32((bits & np.int32(0x007FFFFF)) | np.int32(0x3F800000))
    big = m > F(1.4142135623730951)
    m = m * F(0.5) if big else m
    e = e + np.int32(1) if big else e
    s = (m - F(1.0)) / (m + F(1.0))
    z = s * s
    p = F(1.0 / 9.0)
    p = p * z + F(1.0 / 7.0)
    p = p * z + F(1.0 / 5.0)
    p = p * z + F(1.0 / 3.0)
    p = p * z + F(1.0)
    return F(2.0) * s * p + F(e) * F(0.6931471805599453)


def splat_exp(x):
    """exp used by the splatting kernels (float32: vectorisable polynomial; float64: math.exp)."""
    return math.exp(x)


def splat_log(x):
    """log used by the splatting kernels (float32: vectorisable polynomial; float64: math.log)."""
    return math.log(x)


@overload(splat_exp, jit_options=dict(fastmath={"contract"}, error_model="numpy"))
def _splat_exp_ov(x):
    if x == types.float32:
        return _exp32
    if isinstance(x, types.Float):
        return lambda x: math.exp(x)
    return None


@overload(splat_log, jit_options=dict(fastmath={"contract"}, error_model="numpy"))
def _splat_log_ov(x):
    if x == types.float32:
        return _log32
    if isinstance(x, types.Float):
        return lambda x: math.log(x)
    return None
