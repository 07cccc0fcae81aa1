"""truss_mc: the truss-mc Monte Carlo of a nonlinear space truss, from Python.

Models and single solves (:func:`prism`, :meth:`Model.from_file`, :func:`solve`), jobs run
in-process on all cores (:meth:`Job.from_file`, :meth:`Job.run`, :meth:`Job.inputs`,
:meth:`Job.reproduce`), runs read back (:func:`read_shards`, :func:`read_report`), and
their statistics as ``mc-merge`` computes them (:meth:`Samples.summary`: percentiles with
their intervals, the Rayleigh law's verdicts, the allowable σ, the answer). Every
number comes from the same Rust code as the command-line tools, so it equals what they write,
bit for bit; errors are :mod:`truss_mc.errors` exceptions with the tools' messages. Units:
mm, N, MPa, rad.

    import truss_mc
    s = truss_mc.solve(truss_mc.prism(stages=5), {"longeron.1.0": 0.01})
    s.theta_p  # rad
"""

from __future__ import annotations

from ._native import NUMERICS_VERSION, SHARD_FORMAT_VERSION, __version__
from .errors import (
    InvalidInputError,
    SolveFailedError,
    TrussError,
    TrussIOError,
    UsageError,
    VerificationError,
)
from .job import IndexRange, Job
from .model import Model, Solution, prism, solve
from .results import Inputs, Samples
from .shards import Answer, Report, read_report, read_shards

__all__ = [
    "NUMERICS_VERSION",
    "SHARD_FORMAT_VERSION",
    "__version__",
    "Model",
    "Solution",
    "prism",
    "solve",
    "Job",
    "IndexRange",
    "Samples",
    "Inputs",
    "read_shards",
    "read_report",
    "Report",
    "Answer",
    "TrussError",
    "UsageError",
    "InvalidInputError",
    "TrussIOError",
    "VerificationError",
    "SolveFailedError",
]
