"""Jobs run in-process: a job file's cases solved on all cores with the interpreter lock
released, by the shard runner's own code, so every number equals the shard line's bit for
bit (and the drawn inputs ``mc-shard inputs``'), whatever the thread count."""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Optional, Tuple, Union

from . import _columns, _native
from .errors import UsageError
from .model import Model
from .results import Inputs, Samples

__all__ = ["Job", "IndexRange"]

#: The most threads a run starts (the tools' ``--threads`` bound).
MAX_THREADS = 1024

#: Global sample indices: ``"A..B"``, ``(A, B)`` or ``range(A, B)`` (half-open).
IndexRange = Union[str, Tuple[int, int], range]


def _range_text(r: Optional[IndexRange]) -> Optional[str]:
    if r is None or isinstance(r, str):
        return r
    if isinstance(r, range):
        if r.step != 1:
            raise ValueError(f"range {r!r}: a step other than 1 is not a range of indices")
        return f"{r.start}..{r.stop}"
    start, end = r
    return f"{int(start)}..{int(end)}"


class Job:
    """A validated job: a model, a seed and cases of length-error distributions (see the
    README's "Jobs")."""

    def __init__(self, native: _native.Job) -> None:
        self._native = native

    @staticmethod
    def from_file(path: Union[str, "os.PathLike[str]"]) -> "Job":
        """Reads and validates a job file; a fault raises
        :class:`~truss_mc.errors.InvalidInputError` with the CLI's message and its
        ``json_path``."""
        return Job(_native.Job.from_file(os.fspath(path)))

    @staticmethod
    def from_json(
        text: Union[str, Dict[str, Any]], base: Union[str, "os.PathLike[str]"] = "."
    ) -> "Job":
        """A job from its text (or a dict of it); model files are relative to ``base``."""
        if not isinstance(text, str):
            text = json.dumps(text)
        return Job(_native.Job.from_json(text, os.fspath(base)))

    @property
    def id(self) -> str:
        """The job id: SHA-256 of the job's canonical form and the numerics version."""
        return self._native.id

    @property
    def seed(self) -> int:
        """The seed of every draw."""
        return self._native.seed

    @property
    def samples(self) -> int:
        """Samples over all cases."""
        return self._native.samples

    @property
    def cases(self) -> List[Dict[str, Any]]:
        """The cases: ``name``, ``start`` (global index of the first), ``samples``,
        ``parameters`` (as the shards' header)."""
        return self._native.cases

    def model(self, case: str) -> Model:
        """The model of case ``case``."""
        return Model(self._native.model(case))

    def run(
        self,
        case: Optional[str] = None,
        range: Optional[IndexRange] = None,
        *,
        threads: Optional[int] = None,
        inputs: bool = False,
    ) -> Samples:
        """Solves the samples of ``case`` (every case if None) within the global indices
        ``range`` (all if None) on ``threads`` threads (default: all cores), and returns them
        in index order: the numbers of their shard lines. With ``inputs``, also each sample's
        drawn inputs (:class:`~truss_mc.results.Inputs`). Ctrl-C stops it
        (``KeyboardInterrupt``). :meth:`~truss_mc.results.Samples.summary` gives their
        statistics as ``mc-merge`` computes them."""
        if threads is not None and (
            isinstance(threads, bool) or not isinstance(threads, int) or not 1 <= threads <= MAX_THREADS
        ):
            raise UsageError(f"threads must be 1 to {MAX_THREADS}, not {threads!r}")
        r = self._native.run(case, _range_text(range), threads, inputs)
        raw = r["inputs"]
        return Samples(
            _columns.arrays(r["columns"]),
            inputs=Inputs(raw) if raw is not None else None,
            job_id=self.id,
            cases=self.cases,
            collected=r["collected"],
        )

    def inputs(self, case: Optional[str] = None, range: Optional[IndexRange] = None) -> Inputs:
        """The drawn inputs of ``case``'s samples (every case if None) within ``range``,
        without solving: the rows of ``mc-shard inputs``."""
        return Inputs(self._native.inputs(case, _range_text(range)))

    def reproduce(self, case: str, sample: int, detail: bool = False) -> Any:
        """Sample ``sample`` of case ``case`` again: its shard line (with its newline), as
        ``mc-shard reproduce`` prints it, or with ``detail`` the detail as a dict (draws,
        Newton iterations, displacements, forces)."""
        text = self._native.reproduce(case, sample, detail)
        return json.loads(text) if detail else text

    def __repr__(self) -> str:
        return repr(self._native)
