"""Reading a run back: shard files as :class:`~truss_mc.results.Samples` (verified as the
merge verifies them) and ``report.json`` as tables of arrays."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Dict, Iterable, List, Optional, Union

import numpy as np

from . import _columns, _native
from .errors import InvalidInputError
from .results import Samples

__all__ = ["read_shards", "read_report", "Report", "Answer"]

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
    error here; :meth:`~truss_mc.results.Samples.summary` checks them as ``mc-merge``
    does."""
    r = _native.read_shard_files(_shard_files(paths), partial)
    return Samples(
        _columns.arrays(r["columns"]),
        job_id=r["job_id"],
        cases=r["cases"],
        collected=r["collected"],
    )


def _number(x: Any) -> float:
    return float("nan") if x is None else float(x)


class Answer:
    """The answer of a merge (``report.json``'s ``answer``, computed by ``mc-merge``): each
    case's θ_P at the target percentile against the target, each σ-series' allowable σ, and
    the Rayleigh verdicts with what chance alone gives and Holm's adjustment across the
    cases. Angles in rad, σ in mm, NaN where the report has null."""

    def __init__(self, data: Dict[str, Any], text: Optional[str] = None) -> None:
        #: The parsed ``answer`` section.
        self.data = data
        #: The target angle [rad], as set.
        self.target_angle: float = float(data["target_angle"])
        #: The percentile that must meet it [%].
        self.percentile: float = float(data["percentile"])

        def figure(f: Dict[str, Any], key: str) -> float:
            return _number((f or {}).get(key))

        cases = data["cases"]
        #: Per case: ``case``, ``value`` (θ_P at the target percentile) with ``lower`` and
        #: ``upper`` [rad], and ``against`` (``"above"``, ``"within"``, or ``"undefined"``
        #: where there is no value).
        self.cases: Dict[str, np.ndarray] = {
            "case": np.array([c["case"] for c in cases], dtype=str),
            "value": np.array([figure(c["value"], "value") for c in cases]),
            "lower": np.array([figure(c["value"], "lower") for c in cases]),
            "upper": np.array([figure(c["value"], "upper") for c in cases]),
            "against": np.array([c["against"] for c in cases], dtype=str),
        }
        series = data["allowable_sigma"]
        #: Per σ-series: ``series``, the allowable σ ``value`` with ``lower`` and ``upper``
        #: (the conservative choice) [mm], and ``extrapolated``.
        self.allowable_sigma: Dict[str, np.ndarray] = {
            "series": np.array([a["series"] for a in series], dtype=str),
            "value": np.array([figure(a["sigma"], "value") for a in series]),
            "lower": np.array([figure(a["sigma"], "lower") for a in series]),
            "upper": np.array([figure(a["sigma"], "upper") for a in series]),
            "extrapolated": np.array([bool(a["extrapolated"]) for a in series], dtype=bool),
        }
        r = data["rayleigh"]
        #: Cases whose Rayleigh law was tested.
        self.tested: int = int(r["tested"])
        #: The level α of each test.
        self.level: float = float(r["level"])
        #: Rejections expected by chance alone if the law held in every tested case (m·α).
        self.expected_by_chance: float = float(r["expected_by_chance"])
        #: The cases still rejected after Holm's adjustment across the tested cases.
        self.holm_rejected: List[str] = list(r["holm_rejected"])
        v = r["cases"]
        #: Per tested case: ``case``, ``verdict`` (``"holds"``/``"rejected"``), ``p_value``
        #: (the smaller of KS's and AD's), ``holm_p_value``, and the effect size
        #: ``relative_difference`` ((Rayleigh − empirical)/empirical at the target
        #: percentile) with ``relative_lower`` and ``relative_upper``.
        self.rayleigh: Dict[str, np.ndarray] = {
            "case": np.array([c["case"] for c in v], dtype=str),
            "verdict": np.array([c["verdict"] for c in v], dtype=str),
            "p_value": np.array([float(c["p_value"]) for c in v]),
            "holm_p_value": np.array([float(c["holm_p_value"]) for c in v]),
            "relative_difference": np.array([figure(c["relative_difference"], "value") for c in v]),
            "relative_lower": np.array([figure(c["relative_difference"], "lower") for c in v]),
            "relative_upper": np.array([figure(c["relative_difference"], "upper") for c in v]),
        }
        #: The answer lines ``mc-merge`` ends its console output with (for a summary
        #: computed in-process; None for a report read from a file).
        self.text = text

    @property
    def above(self) -> List[str]:
        """The cases above the target, in job order."""
        return [str(c) for c, a in zip(self.cases["case"], self.cases["against"]) if a == "above"]

    @property
    def within(self) -> List[str]:
        """The cases at or below the target, in job order."""
        return [str(c) for c, a in zip(self.cases["case"], self.cases["against"]) if a == "within"]

    def __str__(self) -> str:
        return self.text if self.text is not None else repr(self)

    def __repr__(self) -> str:
        return (
            f"Answer(target {self.target_angle!r} rad at P{self.percentile:g}: "
            f"{len(self.above)} above, {len(self.within)} within)"
        )


class Report:
    """``report.json`` of ``mc-merge`` (documented in ``crates/mc-merge/README.md``), read
    from a file (:func:`read_report`) or computed in-process by ``mc-merge``'s code
    (:meth:`~truss_mc.results.Samples.summary`): ``data`` is the whole document;
    ``percentiles``, ``cases``, ``rayleigh`` and ``allowable_sigma`` are its main tables as
    arrays (angles in rad, σ in mm, NaN where the report has null), ``answer`` its answer."""

    def __init__(
        self, data: Dict[str, Any], text: Optional[str] = None, answer_text: Optional[str] = None
    ) -> None:
        #: The parsed report.
        self.data = data
        #: The report's JSON text, for one computed in-process (what ``mc-merge`` writes as
        #: ``report.json``); None for one read from a file.
        self.text = text
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

        def figure(x: Any, key: str = "value") -> float:
            return _number(x.get(key)) if isinstance(x, dict) else _number(x)

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
        ray: Dict[str, List[Any]] = {
            k: []
            for k in ("case", "percentile", "value", "lower", "upper", "empirical", "relative_difference")
        }
        for case in cases:
            for p in (case.get("rayleigh") or {}).get("percentiles", []):
                ray["case"].append(case["name"])
                ray["percentile"].append(float(p["percentile"]))
                ray["value"].append(figure(p.get("value")))
                ray["lower"].append(figure(p.get("value"), "lower"))
                ray["upper"].append(figure(p.get("value"), "upper"))
                ray["empirical"].append(_number(p.get("empirical")))
                ray["relative_difference"].append(figure(p.get("relative_difference")))
        #: Per case and percentile, the Rayleigh law's (eq. 28): ``case``, ``percentile``
        #: (%), ``value`` with ``lower`` and ``upper`` [rad], the ``empirical`` percentile
        #: [rad] and their ``relative_difference``.
        self.rayleigh: Dict[str, np.ndarray] = {
            k: np.array(v, dtype=str if k == "case" else np.float64) for k, v in ray.items()
        }
        series = (data.get("sweep") or {}).get("sigma_series", [])
        #: Per σ-series: ``series``, the allowable σ through the origin (``value``, ``lower``,
        #: ``upper``) and with intercept (``with_intercept``, …) [mm], and ``extrapolated``.
        self.allowable_sigma: Dict[str, np.ndarray] = {
            "series": np.array([s["name"] for s in series], dtype=str),
            "value": np.array([figure(s["allowable_sigma"]["through_origin"]) for s in series]),
            "lower": np.array([figure(s["allowable_sigma"]["through_origin"], "lower") for s in series]),
            "upper": np.array([figure(s["allowable_sigma"]["through_origin"], "upper") for s in series]),
            "with_intercept": np.array([figure(s["allowable_sigma"]["with_intercept"]) for s in series]),
            "with_intercept_lower": np.array(
                [figure(s["allowable_sigma"]["with_intercept"], "lower") for s in series]
            ),
            "with_intercept_upper": np.array(
                [figure(s["allowable_sigma"]["with_intercept"], "upper") for s in series]
            ),
            "extrapolated": np.array([bool(s["allowable_sigma"]["extrapolated"]) for s in series], dtype=bool),
        }
        #: The answer (None for a report written before mc-merge wrote one).
        self.answer: Optional[Answer] = (
            Answer(data["answer"], answer_text) if "answer" in data else None
        )

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
