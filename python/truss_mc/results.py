"""Per-sample results as NumPy arrays: :class:`Samples` (one array per field of the shard's
sample lines) and :class:`Inputs` (each sample's drawn length errors and clearances, as
``mc-shard inputs`` writes them)."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any, Dict, Iterator, List, Optional, Sequence

import numpy as np

from . import _columns
from .errors import UsageError

if TYPE_CHECKING:
    from .shards import Report

__all__ = ["Samples", "Inputs"]


class Inputs:
    """Each sample's drawn inputs [mm]: ``values`` has one row per sample and one column per
    member (``length_error:ID``), then per joint of a case that draws clearances
    (``clearance:ID``), in model order; NaN where the sample's model has no such member or
    joint or its case draws no clearances. They are the draws, before gravity or temperature
    add to them: the numbers of ``mc-shard inputs``, bit for bit."""

    def __init__(self, raw: Dict[str, Any]) -> None:
        #: Member ids, the first columns.
        self.member_ids: List[str] = list(raw["member_ids"])
        #: Joint ids, the columns after the members'.
        self.joint_ids: List[str] = list(raw["joint_ids"])
        #: Column names: ``length_error:ID`` …, ``clearance:ID`` ….
        self.columns: List[str] = list(raw["columns"])
        width = len(self.columns)
        values = _columns.floats(raw["values"])
        #: The inputs [mm], shape (samples, members + joints).
        self.values: np.ndarray = values.reshape((len(values) // width if width else 0, width))
        #: Global sample index of each row (from :meth:`Job.inputs`; None from a run, whose
        #: rows are its samples').
        self.index: Optional[np.ndarray] = (
            _columns.ints(raw["index"]) if "index" in raw else None
        )
        #: Case name of each row (from :meth:`Job.inputs`).
        self.case: Optional[np.ndarray] = (
            np.array(raw["case"], dtype=str) if "case" in raw else None
        )
        #: Index within its case of each row (from :meth:`Job.inputs`).
        self.sample: Optional[np.ndarray] = (
            _columns.ints(raw["sample"]) if "sample" in raw else None
        )

    @property
    def length_errors(self) -> np.ndarray:
        """The member length errors [mm], shape (samples, members)."""
        return self.values[:, : len(self.member_ids)]

    @property
    def clearances(self) -> np.ndarray:
        """The joint clearances [mm], shape (samples, joints)."""
        return self.values[:, len(self.member_ids) :]

    def __len__(self) -> int:
        return int(self.values.shape[0])

    def to_pandas(self) -> Any:
        """A pandas DataFrame with ``mc-shard inputs``' columns (needs pandas)."""
        columns: Dict[str, np.ndarray] = {}
        for name in ("index", "case", "sample"):
            value = getattr(self, name)
            if value is not None:
                columns[name] = value
        for j, name in enumerate(self.columns):
            columns[name] = self.values[:, j]
        return _columns.frame(columns)

    def __repr__(self) -> str:
        return f"Inputs({len(self)} samples × {len(self.columns)} columns)"


class Samples:
    """Per-sample results, one NumPy array per field of the shard's sample lines, in index
    order: ``index`` (global), ``case``, ``sample`` (within the case), ``status``
    (``"converged"``/``"failed"``), ``iterations``, ``theta_p`` [rad], ``tan_theta_x``,
    ``tan_theta_y``, ``decenter_x``, ``decenter_y``, ``decenter``, ``despace`` [mm] (where the
    top surface's centroid sits against the bottom's frame; NaN where a record has none),
    ``residual`` [N], ``slack_cables``, ``loose_joints`` (float, NaN where a
    record has none), ``reason`` (empty unless failed), and any other field the lines carry,
    such as ``floating`` (a boolean: 1.0 or 0.0, NaN where a line has none) and
    ``holding_force`` [N] (the largest force on a top node that, to first order, moves
    θ_P by at most 1 % and lets no bearing member go; NaN where a line has none) and
    ``limit_ratio`` (where the solve at the limit did not converge, the compression ratio of
    the continuation's stage that stands for it; NaN where a line has none). Read a field as
    an attribute (``samples.theta_p``) or an item (``samples["theta_p"]``)."""

    def __init__(
        self,
        columns: Dict[str, np.ndarray],
        inputs: Optional[Inputs] = None,
        job_id: Optional[str] = None,
        cases: Optional[List[Dict[str, Any]]] = None,
        collected: Any = None,
    ) -> None:
        self._columns = columns
        # The samples as mc-merge keeps them (native), for summary().
        self._collected = collected
        #: The drawn inputs of each sample, when asked for.
        self.inputs = inputs
        #: The job id, for samples read from shard files.
        self.job_id = job_id
        #: The job's cases (``name``, ``start``, ``samples``, ``parameters``), for samples read
        #: from shard files.
        self.cases = cases

    @property
    def fields(self) -> List[str]:
        """The field names, in the sample lines' order."""
        return list(self._columns)

    @property
    def converged(self) -> np.ndarray:
        """Whether each sample converged."""
        return np.asarray(self._columns["status"] == "converged", dtype=bool)

    def __getitem__(self, name: str) -> np.ndarray:
        return self._columns[name]

    def __getattr__(self, name: str) -> np.ndarray:
        columns: Dict[str, np.ndarray] = self.__dict__.get("_columns", {})
        if name in columns:
            return columns[name]
        raise AttributeError(f"no field {name!r} (fields: {', '.join(columns)})")

    def __contains__(self, name: object) -> bool:
        return name in self._columns

    def __iter__(self) -> Iterator[str]:
        return iter(self._columns)

    def __len__(self) -> int:
        return len(self._columns["index"])

    def to_pandas(self) -> Any:
        """A pandas DataFrame, one column per field (needs pandas)."""
        return _columns.frame(dict(self._columns))

    def summary(
        self,
        *,
        target_angle: Optional[float] = None,
        target_percentile: Optional[float] = None,
        percentiles: Optional[Sequence[float]] = None,
        confidence: Optional[float] = None,
        replicates: Optional[int] = None,
        bootstrap_seed: Optional[int] = None,
        gof_replicates: Optional[int] = None,
        gof_level: Optional[float] = None,
        allow_partial: Optional[bool] = None,
        allow_failed: Optional[bool] = None,
        threads: Optional[int] = None,
    ) -> "Report":
        """The merge's statistics of these samples, computed by ``mc-merge``'s own code
        (nothing is computed in Python): the :class:`~truss_mc.shards.Report` whose ``data``
        is the ``report.json`` that ``mc-merge`` writes for shards of the same samples, byte
        for byte, with its arrays (percentiles with their intervals, the Rayleigh law and
        its verdicts, the allowable σ) and :attr:`~truss_mc.shards.Report.answer` (with the
        console's answer lines as ``answer.text``). The keywords are ``mc-merge``'s settings
        (``target_angle`` is ``--target-angle``, in rad, …), each ``mc-merge``'s default
        where None (9.69e-5 rad at the 95th percentile; percentiles 50, 90, 95, 99; 95 %
        intervals from B = 2000 replicates; 1000 null samples at level 0.05), refused as it
        refuses them. Samples missing from the
        job are refused unless ``allow_partial`` (the default for a run of a case or a range,
        and for ``read_shards(partial=True)``), which marks every figure partial as
        ``mc-merge --allow-partial`` does; failed samples unless ``allow_failed``. Only for
        samples from :meth:`Job.run` or :func:`read_shards`."""
        from .shards import Report

        if self._collected is None:
            raise UsageError(
                "summary() needs samples from Job.run or read_shards (these were built by hand)"
            )
        text, answer = self._collected.report(
            None if percentiles is None else [float(p) for p in percentiles],
            confidence,
            replicates,
            bootstrap_seed,
            gof_replicates,
            gof_level,
            target_angle,
            target_percentile,
            allow_partial,
            allow_failed,
            threads,
        )
        return Report(json.loads(text), text=text, answer_text=answer)

    def __repr__(self) -> str:
        failed = int((~self.converged).sum()) if len(self) else 0
        return f"Samples({len(self)} samples, {failed} failed, fields: {', '.join(self.fields)})"
