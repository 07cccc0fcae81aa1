"""Turns the native module's raw columns (little-endian bytes, lists of strings) into NumPy
arrays, and tables of arrays into pandas frames when pandas is installed."""

from __future__ import annotations

from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

RawColumn = Tuple[str, str, Any, Optional[bytes]]


def floats(data: bytes, shape: Optional[Tuple[int, ...]] = None) -> np.ndarray:
    """A writable float64 array of little-endian bytes."""
    a = np.frombuffer(data, dtype="<f8").astype(np.float64)
    return a.reshape(shape) if shape is not None else a


def ints(data: bytes) -> np.ndarray:
    """A writable int64 array of little-endian bytes."""
    return np.frombuffer(data, dtype="<i8").astype(np.int64)


def arrays(columns: Sequence[RawColumn]) -> Dict[str, np.ndarray]:
    """One array per column: ``int`` columns int64, ``float`` float64, ``bool`` bool,
    ``str`` str; an int or bool column some rows lack becomes float64 with NaN there."""
    out: Dict[str, np.ndarray] = {}
    for name, kind, data, present in columns:
        if kind == "str":
            a = np.array(list(data), dtype=str)
        elif kind == "float":
            a = floats(data)
        elif kind == "int":
            a = ints(data)
        else:
            a = np.frombuffer(data, dtype=np.uint8).astype(bool)
        if present is not None and kind in ("int", "bool"):
            a = a.astype(np.float64)
            a[np.frombuffer(present, dtype=np.uint8) == 0] = np.nan
        out[name] = a
    return out


def frame(columns: Dict[str, np.ndarray], index: Optional[List[str]] = None) -> Any:
    """A pandas DataFrame of the columns (raises ImportError naming pandas without it)."""
    try:
        import pandas
    except ImportError as e:
        raise ImportError(
            "to_pandas() needs pandas, which truss_mc does not depend on: pip install pandas"
        ) from e
    return pandas.DataFrame(columns, index=index)
