"""Reading a run back: shard files as :class:`~truss_mc.results.Samples` (verified as the
merge verifies them) and ``report.json`` as tables of arrays."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Dict, Iterable, List, Union

import numpy as np

from . import _columns, _native
from .errors import InvalidInputError
from .results import Samples

__all__ = ["read_shards", "read_report", "Report"]

PathLike = Union[str, "os.PathLike[str]"]

#: What ``report.json`` says it is (mc-merge's ``REPORT_FORMAT``).
REPORT_FORMAT = "truss-mc-merge-report"

#: The longest ``report.json`` read [bytes] (mc-merge's own bound).
MAX_REPORT_BYTES = 256 << 20


def _shard_files(paths: Union[PathLike, Iterable[PathLike]]) -> List[str]:
    """Each directory's ``*.jsonl`` files (not recursively, sorted by name), each file as
    given: the files ``mc-merge`` takes."""
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    files: List[str] = []
    for p in map(Path, paths):
        if p.is_dir():
            files.extend(sorted(str(f) for f in p.iterdir() if f.suffix == ".jsonl" and f.is_file()))
        else:
            files.append(str(p))
    return files


def read_shards(paths: Union[PathLike, Iterable[PathLike]], *, partial: bool = False) -> Samples:
    """The samples of shard files (directories contribute their ``*.jsonl`` files) in index
    order. Every file is verified as ``mc-merge`` verifies it (each line's form and place,
    every checkpoint, the digests of its end line, a converged θ_P in [0, π/2] rad); files of
    two jobs, or overlapping files whose lines differ, raise
    :class:`~truss_mc.errors.VerificationError`. A path that is not a regular file (a FIFO, a
    device) raises :class:`~truss_mc.errors.InvalidInputError` before it is opened. With ``partial``, an incomplete file (a run
    still going) gives the samples its last checkpoint verifies. Missing ranges are not an
    error here (``mc-merge`` checks coverage)."""
    r = _native.read_shard_files(_shard_files(paths), partial)
    return Samples(_columns.arrays(r["columns"]), job_id=r["job_id"], cases=r["cases"])


def _number(x: Any) -> float:
    return float("nan") if x is None else float(x)


class Report:
    """``report.json`` of ``mc-merge`` (documented in ``crates/mc-merge/README.md``):
    ``data`` is the whole document; ``percentiles`` and ``cases`` are its main tables as
    arrays (angles in rad, NaN where the report has null)."""

    def __init__(self, data: Dict[str, Any]) -> None:
        #: The parsed report.
        self.data = data
        #: The job id.
        self.job_id: str = data["job_id"]
        rows: Dict[str, List[Any]] = {
            k: []
            for k in (
                "case",
                "percentile",
                "value",
                "bootstrap_lower",
                "bootstrap_upper",
                "bca_lower",
                "bca_upper",
                "order_lower",
                "order_upper",
            )
        }
        for case in data["cases"]:
            for p in case.get("percentiles", []):
                rows["case"].append(case["name"])
                rows["percentile"].append(float(p["percentile"]))
                rows["value"].append(_number(p.get("value")))
                for key, name in (
                    ("percentile_bootstrap", "bootstrap"),
                    ("bca", "bca"),
                    ("order_statistic", "order"),
                ):
                    interval = p.get(key) or {}
                    rows[f"{name}_lower"].append(_number(interval.get("lower")))
                    rows[f"{name}_upper"].append(_number(interval.get("upper")))
        #: Per case and percentile: ``case``, ``percentile`` (%), ``value`` [rad] and the
        #: bounds of the percentile-bootstrap, BCa and order-statistic intervals [rad].
        self.percentiles: Dict[str, np.ndarray] = {
            k: np.array(v, dtype=str if k == "case" else np.float64) for k, v in rows.items()
        }

        def figure(x: Any) -> float:
            return _number(x.get("value")) if isinstance(x, dict) else _number(x)

        cases = data["cases"]
        #: Per case: ``name``, ``n`` (samples used), ``failed``, ``sigma_t`` (pooled σ of the
        #: tilts), ``rayleigh_sigma`` [rad], ``gof_verdict``, ``ks_p_value``, ``ad_p_value``.
        self.cases: Dict[str, np.ndarray] = {
            "name": np.array([c["name"] for c in cases], dtype=str),
            "n": np.array([c.get("n", 0) for c in cases], dtype=np.int64),
            "failed": np.array([(c.get("failed") or {}).get("count", 0) for c in cases], dtype=np.int64),
            "sigma_t": np.array([figure((c.get("rayleigh") or {}).get("sigma_t")) for c in cases]),
            "rayleigh_sigma": np.array([figure((c.get("rayleigh") or {}).get("sigma")) for c in cases]),
            "gof_verdict": np.array([str((c.get("gof") or {}).get("verdict", "")) for c in cases], dtype=str),
            "ks_p_value": np.array(
                [_number(((c.get("gof") or {}).get("ks") or {}).get("p_value")) for c in cases]
            ),
            "ad_p_value": np.array(
                [_number(((c.get("gof") or {}).get("ad") or {}).get("p_value")) for c in cases]
            ),
        }

    def percentiles_frame(self) -> Any:
        """``percentiles`` as a pandas DataFrame (needs pandas)."""
        return _columns.frame(self.percentiles)

    def cases_frame(self) -> Any:
        """``cases`` as a pandas DataFrame (needs pandas)."""
        return _columns.frame(self.cases)

    def __repr__(self) -> str:
        return f"Report(job {self.job_id[:12]}…, {len(self.cases['name'])} cases)"


def read_report(path: PathLike) -> Report:
    """Reads ``report.json`` (or the report directory holding it). A path that is not a
    regular file (a FIFO, a device) is refused before it is opened, and a file that is not a
    whole mc-merge report raises :class:`~truss_mc.errors.InvalidInputError`."""
    p = Path(path)
    if p.is_dir():
        p = p / "report.json"
    # The file type before the open: a FIFO would block it, a device never end.
    if p.exists() and not p.is_file():
        raise InvalidInputError(f"{p}: not a regular file; give the path of a report.json")
    if p.exists() and p.stat().st_size > MAX_REPORT_BYTES:
        raise InvalidInputError(f"{p}: longer than {MAX_REPORT_BYTES} bytes, not a report")
    with open(p, encoding="utf-8") as f:
        try:
            data = json.load(f, parse_constant=lambda c: math.nan)
        except ValueError as e:  # not JSON, not UTF-8
            raise InvalidInputError(f"{p}: not a readable mc-merge report ({e})") from e
    if not isinstance(data, dict) or data.get("format") != REPORT_FORMAT:
        raise InvalidInputError(f'{p}: not an mc-merge report (no "format": "{REPORT_FORMAT}")')
    try:
        return Report(data)
    except (KeyError, TypeError, ValueError, AttributeError) as e:
        raise InvalidInputError(f"{p}: a malformed mc-merge report ({type(e).__name__}: {e})") from e
