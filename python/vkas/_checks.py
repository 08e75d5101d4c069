"""Argument checks and conversions of the vkas package: arrays (float32 read in place, float64 converted once),
indices, transforms, bools, ints and the tmin/tmax arguments of tracing."""

import numbers

import numpy as np


# Argument checks. The rule: float32 arrays are read in place, so they must be C-contiguous (a float32 array that is
# not raises ValueError: pass np.ascontiguousarray(a)); float64 arrays (and array-likes such as lists of floats)
# are converted to float32 once, whatever their layout. Any other dtype is a TypeError.

def _shape_text(shape):
    return "(" + ", ".join(str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def _an(desc):
    return ("an " if desc[:1] in "(aeiou" and not desc.startswith("(3") else "a ") + desc


def _float32(value, name, desc, shape_ok):
    """value as a C-contiguous float32 array; desc like '(R, 3)' for the messages; shape_ok(shape) -> bool."""
    try:
        a = np.asarray(value)
    except Exception as e:  # numpy raises for ragged lists and exotic objects
        raise TypeError(f"{name}: expected {_an(desc)} float32 array, got {type(value).__name__} that numpy cannot "
                        f"read as an array ({e})") from e
    if a.dtype == np.float32:
        if not shape_ok(a.shape):
            raise ValueError(f"{name}: expected {_an(desc)} float32 array, got shape {_shape_text(a.shape)}")
        if not a.flags.c_contiguous:
            raise ValueError(f"{name}: the float32 array is not C-contiguous; vkas reads float32 arrays in place "
                             f"and does not copy them behind your back: pass np.ascontiguousarray({name})")
        if not a.flags.aligned:
            raise ValueError(f"{name}: the float32 array is not aligned to 4 bytes; vkas reads float32 arrays in "
                             f"place and does not copy them behind your back: pass np.require({name}, "
                             f"requirements='CA')")
        return a
    if a.dtype == np.float64:
        if not shape_ok(a.shape):
            raise ValueError(f"{name}: expected {_an(desc)} float32 array, got shape {_shape_text(a.shape)}")
        with np.errstate(over="ignore"):
            return np.ascontiguousarray(a, dtype=np.float32)
    raise TypeError(f"{name}: expected {_an(desc)} float32 array (float64 is converted), got dtype {a.dtype}"
                    + (f" ({type(value).__name__})" if not isinstance(value, np.ndarray) else ""))


def _rows3(shape):
    return len(shape) == 2 and shape[1] == 3


def _first_bad(mask):
    return int(np.flatnonzero(mask)[0])


def _check_finite(a, name, what="values"):
    ok = np.isfinite(a)
    if not ok.all():
        i = np.unravel_index(_first_bad(~ok.ravel()), a.shape)
        where = f"[{', '.join(str(int(k)) for k in i)}]"
        raise ValueError(f"{name}: {what} must be finite, {name}{where} is {a[i]}")


def _bool(value, name):
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise TypeError(f"{name}: expected a bool, got {type(value).__name__}")


def _int(value, name, lo, hi):
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name}: expected an int, got {type(value).__name__}")
    v = int(value)
    if not lo <= v <= hi:
        raise ValueError(f"{name}: must be in [{lo}, {hi if hi < 4096 else hex(hi)}], got {v}")
    return v


def _transform(value, name):
    """(3, 4) row-major affine transform (a (4, 4) one with last row 0 0 0 1 is accepted), or None."""
    if value is None:
        return None
    t = _float32(value, name, "(3, 4)", lambda s: s in ((3, 4), (4, 4)))
    _check_finite(t, name)
    if t.shape == (4, 4):
        if not np.array_equal(t[3], np.array([0, 0, 0, 1], dtype=np.float32)):
            raise ValueError(f"{name}: a (4, 4) transform must be affine (last row 0 0 0 1), got {t[3].tolist()}")
        t = np.ascontiguousarray(t[:3])
    return t


def _indices(value, nvertices):
    try:
        a = np.asarray(value)
    except Exception as e:  # pragma: no cover
        raise TypeError(f"indices: expected an (M, 3) uint16/uint32/int32 array, got {type(value).__name__}") from e
    if a.dtype == np.bool_ or not np.issubdtype(a.dtype, np.integer):
        raise TypeError(f"indices: expected an (M, 3) uint16/uint32/int32 array, got dtype {a.dtype}")
    if not _rows3(a.shape):
        raise ValueError(f"indices: expected an (M, 3) uint16/uint32/int32 array, got shape {_shape_text(a.shape)}")
    if a.size:
        lo, hi = int(a.min()), int(a.max())
        if lo < 0 or hi >= nvertices:
            bad = (a < 0) | (a >= nvertices)
            face = _first_bad(bad.any(axis=1))
            raise ValueError(f"indices: face {face} is {a[face].tolist()}, out of range for {nvertices} vertices")
    if a.dtype in (np.uint16, np.uint32) and a.dtype.isnative:
        if not a.flags.c_contiguous:
            raise ValueError("indices: the array is not C-contiguous; vkas reads uint16/uint32 indices in place: "
                             "pass np.ascontiguousarray(indices)")
        if not a.flags.aligned:
            raise ValueError(f"indices: the {a.dtype} array is not aligned to {a.dtype.itemsize} bytes; vkas reads "
                             "uint16/uint32 indices in place: pass np.require(indices, requirements='CA')")
        return a
    return np.ascontiguousarray(a, dtype=np.uint32)  # int32, int64, ...: range checked above


def _ndim(value, name, desc):
    """np.ndim(value), or TypeError naming the argument where numpy cannot make an array of it (ragged lists)."""
    try:
        return np.ndim(value)
    except Exception as e:
        raise TypeError(f"{name}: expected {desc}, got {type(value).__name__} that numpy cannot read as an array "
                        f"({e})") from e


def _t(value, name, count):
    if _ndim(value, name, "a number or an (R,) float32 array") == 0:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.ndarray)):
            raise TypeError(f"{name}: expected a number or an (R,) float32 array, got {type(value).__name__}")
        if isinstance(value, np.ndarray) and not np.issubdtype(value.dtype, np.floating) \
                and not np.issubdtype(value.dtype, np.integer):
            raise TypeError(f"{name}: expected a number or an (R,) float32 array, got dtype {value.dtype}")
        with np.errstate(over="ignore"):
            return np.array(value, dtype=np.float32)
    return _float32(value, name, f"(R,) (R = {count})", lambda s: s == (count,))
